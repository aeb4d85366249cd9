/* recon_params.h - a tr_recon_params as the reconstruction uses it: a field whose zero
 * would divide by zero (a history cap, a Gaussian's sigma) takes its default when it is
 * 0, so that a zero-initialised tr_recon_params means tr_recon_params_default() there.
 * Fields whose zero is a setting (alpha_min, the radius and iteration counts, the
 * switches, emission_samples) are kept as given. Internal to src/post. */
#ifndef TRAC0R_POST_RECON_PARAMS_H
#define TRAC0R_POST_RECON_PARAMS_H

#include "trac0r/post.h"

static inline tr_recon_params tr_recon_params_resolve(const tr_recon_params *p) {
    const tr_recon_params d = tr_recon_params_default();
    tr_recon_params r = *p;
#define TR_RECON_PARAM_OR_DEFAULT(field)                                                           \
    if (r.field == 0.0f) {                                                                         \
        r.field = d.field;                                                                         \
    }
    TR_RECON_PARAM_OR_DEFAULT(max_len)
    TR_RECON_PARAM_OR_DEFAULT(max_len_moving)
    TR_RECON_PARAM_OR_DEFAULT(bilateral_sigma_s)
    TR_RECON_PARAM_OR_DEFAULT(bilateral_sigma_r)
    TR_RECON_PARAM_OR_DEFAULT(atrous_sigma_c)
    TR_RECON_PARAM_OR_DEFAULT(atrous_sigma_n)
    TR_RECON_PARAM_OR_DEFAULT(atrous_sigma_z)
    TR_RECON_PARAM_OR_DEFAULT(atrous_sigma_a)
#undef TR_RECON_PARAM_OR_DEFAULT
    return r;
}

/* The parameters one method's frame uses: resolved, and SVGF's own alpha_min where it
 * has one. */
static inline tr_recon_params tr_recon_params_for(const tr_recon_params *p, int method) {
    tr_recon_params r = tr_recon_params_resolve(p);
    if (method == TR_RECON_SVGF && r.svgf_alpha_min > 0.0f) {
        r.alpha_min = r.svgf_alpha_min;
    }
    return r;
}

#endif

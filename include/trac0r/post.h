/* post.h - what happens to a film after rendering: tonemapping for display and files,
 * and the error metrics of an image against a reference.
 *
 * Usage:
 *
 *     uint32_t *argb = malloc(w * h * 4);   (the viewer's texture)
 *     tr_tonemap_film(&film, 0, 0, w, h, exposure, TR_PIXEL_ARGB8888, argb, w * 4, &err);
 *
 *     tr_image_metrics m = tr_image_compare(a.rgb, ref.rgb, (size_t)w * h);
 *     printf("rmse %g psnr %g dB\n", m.rmse, m.psnr);
 *
 * The per-pixel tonemap is single-source (src/post/tonemap.h) so that a device can run
 * it too; these functions are its host side. Plain C99 / C++, no kernel headers. */
#ifndef TRAC0R_POST_H
#define TRAC0R_POST_H

#include <stddef.h>
#include <stdint.h>

#include "trac0r/error.h"
#include "trac0r/types.h"

#ifdef __cplusplus
extern "C" {
#endif

struct tr_film;

/* ---- Tonemapping --------------------------------------------------------------- */

/* Tonemaps one linear value: scale by 2^exposure, clamp to [0,1] (NaN and negatives
 * are black), sRGB transfer, 8 bits. */
uint8_t tr_tonemap_srgb8(float linear, float exposure);

/* The sRGB transfer function's inverse: an sRGB-encoded value in [0,1] to linear. */
float tr_srgb_to_linear(float encoded);

typedef enum tr_pixel_format {
    TR_PIXEL_RGB8 = 1,     /* 3 bytes per pixel: R, G, B */
    TR_PIXEL_ARGB8888 = 2, /* one uint32_t per pixel, 0xAARRGGBB with alpha 255 */
} tr_pixel_format;

/* Tonemaps the film's mean radiance in the rectangle at (x, y) of size width x height
 * into dst (row r of the rectangle at dst + r * dst_stride bytes; pixels where no
 * sample landed are black), exactly as tr_tonemap_srgb8 maps each channel. Runs on the
 * calling thread only (split the film into rectangles for more). Fails on a rectangle
 * outside the film, an empty one, an unknown format or a stride smaller than a row. */
int tr_tonemap_film(const struct tr_film *film, uint32_t x, uint32_t y, uint32_t width,
                    uint32_t height, float exposure, tr_pixel_format format, void *dst,
                    size_t dst_stride, tr_error *err);

/* Display curves: the hard clamp (the default: bytes as before), or a filmic curve
 * (Narkowicz's fit of ACES, src/post/tonemap.h) that rolls highlights off. */
typedef enum tr_tonemap_curve_kind {
    TR_TONEMAP_CLAMP = 0,
    TR_TONEMAP_FILMIC = 1
} tr_tonemap_curve_kind;

/* "clamp" or "filmic"; NULL for anything else. */
const char *tr_tonemap_curve_name(int curve);
/* The curve of a name above; -1 for anything else. */
int tr_tonemap_curve_parse(const char *name);

/* tr_tonemap_film through `curve` (TR_TONEMAP_CLAMP: tr_tonemap_film's bytes). */
int tr_tonemap_film_curve(const struct tr_film *film, uint32_t x, uint32_t y, uint32_t width,
                          uint32_t height, float exposure, int curve, tr_pixel_format format,
                          void *dst, size_t dst_stride, tr_error *err);

/* A new radiance-only film (free it with tr_film_free) holding `in`'s display-referred
 * values: each mean scaled by 2^exposure and put through `curve`, one sample per pixel
 * (none where `in` has none). Written as PNG at exposure 0 it gives exactly the bytes of
 * tr_tonemap_film_curve: how `--tonemap filmic` reaches the PNG writer. */
int tr_tonemap_display_film(const struct tr_film *in, float exposure, int curve,
                            struct tr_film *out, tr_error *err);

/* Whether `film` at `exposure` shows anything: 1 when nearly every pixel (99.9 %) displays
 * black, 2 when nearly every pixel (99 %) is clipped white, each with a sentence in buf
 * saying what usually causes it; 0 (buf empty) otherwise, and for a film without samples.
 * What a program prints after a render so that a black or white image is not silent. */
int tr_image_exposure_note(const struct tr_film *film, float exposure, char *buf, size_t n);

/* ---- Image metrics ------------------------------------------------------------- */

/* The epsilon of the relative MSE's denominator, ref^2 + epsilon. */
#define TR_RELMSE_EPSILON 0.01

/* Errors of an image against a reference, over every pixel and channel, on values
 * clamped to [0,1] (NaN counts as 0). */
typedef struct tr_image_metrics {
    double mse;       /* mean of (a - ref)^2 */
    double rmse;      /* sqrt(mse) */
    double relmse;    /* mean of (a - ref)^2 / (ref^2 + TR_RELMSE_EPSILON) */
    double psnr;      /* tr_psnr(mse): dB, peak 1; +inf for identical images */
    double max_error; /* the largest tr_pixel_error over the pixels */
} tr_image_metrics;

/* Metrics of `a` against the reference `ref` (3 floats per pixel, linear RGB). The
 * sums run in pixel order, so the result never depends on the thread count. */
tr_image_metrics tr_image_compare(const float *a, const float *ref, size_t pixels);

/* One pixel's error: the mean over R, G, B of |a - ref| on values clamped as above. */
double tr_pixel_error(const float *a_rgb, const float *ref_rgb);

/* The structural similarity index (SSIM, Wang et al. 2004) of `a` against `ref` (3
 * floats per pixel, width x height) on the luminance of values clamped as above: 1 for
 * identical images, less the more their local structure differs. Sequential, so the same
 * on every run; NaN only when memory runs out. */
double tr_ssim(const float *a, const float *ref, uint32_t width, uint32_t height);

/* Peak signal-to-noise ratio of an MSE, peak 1: 10 log10(1 / mse) dB; +inf where mse is
 * not above 0. */
double tr_psnr(double mse);

/* Writes the per-pixel error of `a` against `ref` (tr_pixel_error; 3 floats per pixel,
 * width x height) to `path` (.png or .pfm, as tr_film_write) as a false-colour image:
 * black for none, through blue, magenta, orange and yellow, to white at `max` and above
 * (tr_image_metrics.max_error for the image's own largest). */
int tr_error_map_write(const float *a, const float *ref, uint32_t width, uint32_t height,
                       double max, const char *path, tr_error *err);

/* ---- Real-time reconstruction --------------------------------------------------- */

/* One frame's mean radiance and passes, planar, row-major, top row first. */
typedef struct tr_gbuffer {
    uint32_t width, height;
    float *color;     /* 3 floats per pixel: linear radiance */
    float *albedo;    /* 3 per pixel */
    float *normal;    /* 3 per pixel, unit (zero where nothing was hit) */
    float *depth;     /* 1 per pixel: distance along the camera ray, 0 where nothing was hit */
    uint32_t *prim;   /* 1 per pixel: triangle index + 1, 0 where nothing was hit */
    float *direct;    /* 3 per pixel: the direct part of color (TR_PASS_DIRECT) */
    int has_direct;   /* whether direct holds the film's direct pass (else it is not read) */
    float *emission;  /* 3 per pixel: the first hit's emission in color (TR_PASS_EMISSION) */
    int has_emission; /* whether emission holds the film's emission pass (else not read) */
    float *emission_resolved; /* 3 per pixel: the emission resolved over each pixel's area */
    int has_resolved;         /* whether emission_resolved is set (tr_resolve_emission) */
    uint8_t *scratch;         /* 3 bytes per pixel for tr_resolve_emission, allocated once */
    float *specular;          /* 8 per pixel: the means of TR_PASS_SPECULAR (types.h) */
    int has_specular;         /* whether specular holds the film's specular pass */
} tr_gbuffer;

int tr_gbuffer_init(tr_gbuffer *g, uint32_t width, uint32_t height, tr_error *err);
void tr_gbuffer_free(tr_gbuffer *g);
/* The film's means into g (of the film's size). A pass the film lacks reads as albedo 1,
 * normal, depth and id 0 (the guided filters then fall back on colour alone); has_direct
 * and has_emission say whether the film kept the direct and emission passes; has_resolved
 * is cleared. */
int tr_gbuffer_from_film(tr_gbuffer *g, const struct tr_film *film, tr_error *err);

/* What tr_recon_frame does to a frame, each method one stage more than "accumulate". */
typedef enum tr_recon_method {
    TR_RECON_OFF = 0,        /* the frame as rendered */
    TR_RECON_ACCUMULATE = 1, /* temporal accumulation with reprojection */
    TR_RECON_BILATERAL = 2,  /* ... then the bilateral filter (the thesis's baseline) */
    TR_RECON_ATROUS = 3,     /* ... then edge-avoiding à-trous (Dammertz et al. 2010) */
    TR_RECON_SVGF = 4,       /* ... then variance-guided à-trous (Schied et al. 2017) */
    TR_RECON_COUNT = 5
} tr_recon_method;

/* "off", "accumulate", "bilateral", "atrous", "svgf"; NULL for anything else. */
const char *tr_recon_name(int method);
/* The method of a name above; -1 for anything else. */
int tr_recon_parse(const char *name);

typedef struct tr_recon_params {
    float alpha_min;      /* the EMA's smallest new-sample weight (0.2 in SVGF) */
    float max_len;        /* history length cap (frames) */
    float max_len_moving; /* the cap where the surface moved since the previous frame (its
                             primitive's motion, tr_recon_frame_moving), so that its
                             changing shading does not lag behind */
    int bilateral_radius; /* window (2r+1)^2 */
    float bilateral_sigma_s, bilateral_sigma_r;
    int atrous_iterations; /* à-trous's steps 1, 2, 4, ... */
    float atrous_sigma_c, atrous_sigma_n, atrous_sigma_z, atrous_sigma_a;
    int svgf_iterations; /* SVGF's à-trous steps 1, 2, 4, ... */
    float svgf_sigma_l, svgf_sigma_n, svgf_sigma_z;
    int svgf_feedback;    /* 1: the first SVGF iteration's output becomes the history */
    float svgf_taa_alpha; /* SVGF's temporal antialiasing: new-frame weight (0: off) */
    int svgf_split;       /* 1: SVGF filters direct and indirect apart where the frame has the
                             direct pass (Schied et al. 2017, section 4) */
    int emission_samples; /* n of tr_resolve_emission for the callers that resolve the
                             emission (bench realtime, view): n x n rays per edge pixel;
                             0: they keep the emission in the filtered frame */
    int gradients;        /* 1: tr_realtime measures temporal gradients (A-SVGF, Schied et
                             al. 2018: a sparse replay of the previous frame's samples in the
                             current scene) and shortens the history where the shading
                             changed, through tr_recon.len_cap; 0: off (docs/realtime.md) */
    int svgf_specular;    /* 1: SVGF filters the diffuse and the specular light apart where
                             the frame has the specular pass, each demodulated by its own
                             albedo, the specular history following reflections
                             (docs/realtime.md); 0: off */
    int albedo_samples;   /* n of tr_resolve_albedo for the callers that resolve the albedo
                             (tr_realtime, bench realtime, view): n x n rays per pixel;
                             0: the reconstruction multiplies by the sample's own albedo */
    float albedo_alpha;   /* SVGF multiplies the filtered illumination back by an albedo
                             kept through the temporal stage's reprojection, this frame's
                             weighing albedo_alpha (or 1 / the history's length when
                             larger): each frame's jittered sample falls on another side
                             of a texture's edge, and the history converges to the pixel's
                             mean. 0: this frame's sample; default 0.35. The host's and
                             an OpenCL device's reconstruction (docs/realtime.md) */
    float svgf_alpha_min; /* alpha_min for SVGF's temporal stage (the other methods keep
                             alpha_min); 0: alpha_min */
    int upscale_albedo;   /* tr_realtime's upscaled frames: 1 (default): the light is
                             upscaled apart from the albedo - the traced frame's
                             reconstruction divided by the albedo it was multiplied by,
                             upscaled, then multiplied by the output's albedo
                             (tr_upscale_albedo: the frame's interpolated where it is flat,
                             a first-hit ray through the output pixel's centre elsewhere),
                             so that textures and material edges are sharp at the output's
                             resolution; 0: the remodulated colour is upscaled
                             (docs/realtime.md) */
    int fresh_spp;        /* tr_realtime, where the film lies: the samples per pixel in all
                             of the pixels without history (the first frame, a cut, a
                             disocclusion), traced again after the frame's own; at most the
                             frame's samples: none (docs/realtime.md) */
} tr_recon_params;

/* The defaults. A field that would divide by zero at 0 (max_len, max_len_moving, the
 * bilateral and à-trous sigmas) takes its default when 0; the others are used as given,
 * so a zero-initialised tr_recon_params differs from the defaults in alpha_min,
 * bilateral_radius, the iteration counts, svgf_feedback, emission_samples,
 * svgf_alpha_min, albedo_alpha, upscale_albedo and fresh_spp. */
tr_recon_params tr_recon_params_default(void);

/* The reconstruction's state between frames (history and scratch buffers): the caller
 * owns it; nothing else is kept between calls. */
typedef struct tr_recon {
    uint32_t width, height;
    int have_history;
    tr_camera prev_cam;
    int cur;                /* which of the two history buffers is the newest */
    float *hist_color[2];   /* demodulated illumination, 3 per pixel */
    float *hist_albedo[2];  /* albedo_alpha's albedo history, 3 per pixel */
    int have_albedo;        /* hist_albedo[cur] holds the last frame's (albedo_alpha > 0) */
    float *hist_moments[2]; /* luminance mean and mean square, 2 per pixel */
    float *hist_len[2];     /* frames of history */
    float *temporal;        /* the host temporal stage's planes: points, projection */
    float *hist_depth, *hist_normal;
    uint32_t *hist_prim;
    float *illum; /* scratch, 3 floats per pixel */
    float *soa;   /* scratch planes of the spatial filters */
    float *taa;   /* SVGF's last output, for temporal antialiasing */
    /* SVGF with direct and indirect apart: then hist_color and hist_moments hold the
     * indirect part and these the direct one (demodulated, luminance moments). */
    float *hist_direct[2], *hist_dmoments[2];
    float *illum_d;                 /* scratch: this frame's demodulated direct illumination */
    float *reflected, *reflected_d; /* scratch: colour and direct less the frame's emission */
    int hist_split;                 /* whether the history was written split */
    int have_taa;
    double ms_temporal, ms_spatial; /* the stages' wall times in the last tr_recon_frame */
    /* Per pixel, the most frames of history the next tr_recon_frame keeps (a cap under
     * max_len, 1: the history is dropped), width x height floats the caller owns and
     * sets before the call (tr_realtime's temporal gradients); NULL (after tr_recon_init):
     * none. The host reconstruction only. */
    const float *len_cap;
    /* Asked between the spatial filters' iterations, set by the caller before a call like
     * len_cap (NULL after tr_recon_init: never): nonzero stops the frame, which then fails
     * with TR_STATUS_CANCELLED, its output unfinished, its history kept. The host
     * reconstruction only. */
    int (*cancel)(void *user);
    void *cancel_user;
    /* SVGF with diffuse and specular apart (svgf_specular): then hist_color, hist_moments
     * and hist_len hold the diffuse part and these the specular one (demodulated by the
     * specular albedo), with its own lengths. */
    float *hist_spec[2], *hist_smoments[2], *hist_slen[2];
    float *illum_s;      /* scratch: this frame's demodulated specular illumination */
    float *spec_alb;     /* scratch: this frame's specular albedo, 3 per pixel */
    float *diffuse;      /* scratch: this frame's diffuse light (colour less emission, specular) */
    int hist_spec_split; /* whether the history was written with the specular apart */
} tr_recon;

int tr_recon_init(tr_recon *r, uint32_t width, uint32_t height, tr_error *err);
void tr_recon_free(tr_recon *r);
/* Forgets the history (a camera cut, a new scene). */
void tr_recon_clear(tr_recon *r);
/* Reconstructs frame g, rendered through cam, with `method` into out (3 floats per
 * pixel), on up to `threads` OpenMP threads (0: the default); the result does not
 * depend on the thread count. The history then holds this frame. Fails on a size other
 * than the state's or an unknown method. A frame with the emission pass (has_emission) is
 * filtered without it, and it is added to the result after: emission_resolved where
 * has_resolved is set, else the frame's own (method "off" leaves the frame as it is). */
int tr_recon_frame(tr_recon *r, const tr_gbuffer *g, const tr_camera *cam, int method,
                   const tr_recon_params *p, int threads, float *out, tr_error *err);
/* tr_recon_frame for a scene whose shapes move (view --animate): motion[id] is how far
 * primitive id (the prim pass: triangle index + 1) moved in world space since the
 * previous frame, for ids below motion_count (others, and all when motion is NULL, did
 * not move). The temporal stage follows each pixel's surface back by its primitive's
 * motion, so that the history of a moving shape stays with it (per-primitive motion
 * vectors) instead of being rejected. */
int tr_recon_frame_moving(tr_recon *r, const tr_gbuffer *g, const tr_camera *cam,
                          const tr_vec3 *motion, uint32_t motion_count, int method,
                          const tr_recon_params *p, int threads, float *out, tr_error *err);

/* The largest n of tr_resolve_emission. */
#define TR_RESOLVE_EMISSION_MAX 16

struct tr_scene;
/* Resolves g's emission (the first hit's, TR_PASS_EMISSION) over each pixel's area where
 * it matters: every pixel next to an edge between pixels whose sample saw emission and
 * pixels whose sample did not traces n x n camera rays through `cam` (the frame's camera),
 * spread over the pixel as a Hammersley set (a (0, 2)-net where n x n is a power of two),
 * into the committed scene and takes the mean emission they see at their first hit (where
 * exactly one of them sees any, the mean of 4 n x n rays instead: a thin sliver of a bright
 * lamp); other pixels keep their own. The result goes to g->emission_resolved and
 * g->has_resolved is set, so that tr_recon_frame adds it after filtering: a lamp's edge
 * antialiased at one sample per pixel. n in 1..TR_RESOLVE_EMISSION_MAX; `resolved` (may
 * be NULL) gets the number of pixels traced. Runs on the host on up to `threads` threads
 * (0: the default), whatever device rendered the frame. */
int tr_resolve_emission(const struct tr_scene *scene, const tr_camera *cam, int n, int threads,
                        tr_gbuffer *g, uint32_t *resolved, tr_error *err);

/* The largest n of tr_resolve_albedo, and the albedo difference that marks an edge. */
#define TR_RESOLVE_ALBEDO_MAX 8
#define TR_RESOLVE_ALBEDO_STEP 0.02f

/* Resolves g's albedo over the area of the pixels where it varies: every pixel whose
 * albedo differs from one of its 8 neighbours' by more than TR_RESOLVE_ALBEDO_STEP in a
 * channel (a texture's or a material's edge, an outline) traces an n x n grid of camera
 * rays through `cam` (the frame's camera, pinhole) into the committed scene and takes the
 * mean base colour of the first surfaces they find that are not perfect mirrors or smooth
 * glass (through those, the surface primary surface replacement records), over the rays
 * that find one. That mean replaces the pixel's albedo in g->albedo, so that
 * tr_recon_frame demodulates and remodulates by it: at one sample per pixel the sample's
 * own albedo is one side of the edge or the other, which re-aliases the edge every frame.
 * n in 1..TR_RESOLVE_ALBEDO_MAX; `resolved` (may be NULL) gets the number of pixels
 * traced. Runs on the host on up to `threads` threads (0: the default); uses g->scratch. */
int tr_resolve_albedo(const struct tr_scene *scene, const tr_camera *cam, int n, int threads,
                      tr_gbuffer *g, uint32_t *resolved, tr_error *err);
/* The albedo the reconstruction multiplies by (the kernel's tr_first_albedo: a glossy
 * surface's directional albedo) of one first-hit ray through the centre of every pixel of
 * cam, 3 floats per pixel into out (0 where the ray hits nothing), on up to `threads`
 * threads (0: the default), into the committed scene. tr_upscale_albedo (upscale.h) traces
 * the same rays for an upscaled frame's output only where the frame's own albedo does not
 * give it; this traces them all (its reference in the tests). */
int tr_albedo_image(const struct tr_scene *scene, const tr_camera *cam, int threads, float *out,
                    tr_error *err);

/* The spatial filters alone, on one image `in` (3 floats per pixel) guided by g's
 * passes (`trac0r render --denoise`): the bilateral filter on radiance, à-trous on
 * demodulated radiance. */
int tr_filter_bilateral(const tr_gbuffer *g, const float *in, float *out, const tr_recon_params *p,
                        int threads, tr_error *err);
int tr_filter_atrous(const tr_gbuffer *g, const float *in, float *out, const tr_recon_params *p,
                     int threads, tr_error *err);

/* The offline denoiser (src/post/denoise.c): a finished film's radiance cleaned with its
 * feature passes. Fireflies are re-weighted from the pixels' own sample statistics (the
 * film's TR_PASS_VARIANCE sums of squares: a spike above its neighbourhood that its
 * samples cannot vouch for is brought back to it), the first hit's emission
 * (TR_PASS_EMISSION) is kept apart and filtered along the edges of emitters, and the
 * illumination (radiance / albedo) is a first-order regression on normal, depth and
 * screen position over a window around each pixel, at window radii from radius_small
 * doubling up to radius, or an edge-stopping a-trous level; each pixel takes the
 * candidate, or its own value, of least estimated error (Stein's unbiased risk estimate
 * from the sums of squares). Zero fields take their defaults. */
typedef struct tr_denoise_params {
    int radius;       /* the large window's half-width in pixels, 1..64 (default 4) */
    int radius_small; /* the small window's, 1..64 (default 1) */
    float firefly_k;  /* standard errors a spike keeps (default 3): larger keeps more */
} tr_denoise_params;

tr_denoise_params tr_denoise_params_default(void);
/* Denoises `film`, which must keep the albedo, normal and depth passes (the variance and
 * emission passes are used when kept; without the variance pass every spike above its
 * neighbourhood is taken for a firefly), into out (3 floats per pixel, the film's size),
 * on up to `threads` OpenMP threads (0: the default); the result does not depend on the
 * thread count. params may be NULL (the defaults). */
int tr_denoise_film(const struct tr_film *film, const tr_denoise_params *params, int threads,
                    float *out, tr_error *err);

#ifdef __cplusplus
}
#endif

#endif

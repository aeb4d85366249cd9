/* dfg.h - the GGX lobe's pre-integrated directional albedo (the "DFG" table of real-time
 * shading, after Karis, "Real Shading in Unreal Engine 4", SIGGRAPH 2013 course): with
 * Schlick's Fresnel F = F0 + (1 - F0) (1 - wo.h)^5 the albedo of the single-scattering GGX
 * lobe of bsdf.h (height-correlated Smith G2) is linear in F0,
 *
 *   E(F0, mu, alpha) = int f cos dwi = F0 A(mu, alpha) + B(mu, alpha),
 *   A = int (D G2 / (4 mu cos_i)) (1 - Fc) cos_i dwi,  B = int (...) Fc cos_i dwi,
 *   Fc = (1 - wo.h)^5, mu = cos(wo, n),
 *
 * so a table of A and B over (mu, alpha) gives any F0's albedo. The real-time
 * reconstruction divides the specular part of a pixel's light by it (demodulation, as it
 * divides the diffuse part by the albedo pass). The table is computed once per process
 * (tr_post_dfg_table) by integrating the kernel's own visible-normal sampler: on each node,
 * TR_DFG_SAMPLES^2 stratified midpoints of the sampler's unit square, each weighing
 * G2 / G1(wo) (f cos / pdf with F = 1), split by Fc. Nodes: mu_i = max(i / (N - 1), 1e-3),
 * alpha_j = max(j / (N - 1), TR_GGX_MIN_ALPHA); read with bilinear interpolation. */
#ifndef TR_POST_DFG_H
#define TR_POST_DFG_H

#include "kernel/types.h"
#include "post/filter.h" /* TR_DFG_N and the lookup's arithmetic (tr_post_dfg_at) */
#define TR_DFG_SAMPLES 64

/* The table: A at [2 (j N + i)], B at [2 (j N + i) + 1]; computed on the first call, then
 * shared (read-only). */
const float *tr_post_dfg_table(void);
/* A and B at node (i, j), integrated with s x s stratified samples (the table's entries
 * with s = TR_DFG_SAMPLES). */
void tr_post_dfg_node(int i, int j, int s, float *a, float *b);
/* The node coordinates. */
float tr_post_dfg_mu(int i);
float tr_post_dfg_alpha(int j);
/* A and B at (mu, alpha), bilinear between the nodes (clamped to the table). */
void tr_post_dfg_lookup(const float *table, float mu, float alpha, float *a, float *b);

#endif

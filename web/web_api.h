/* web_api.h - the C interface of the web build's module (web/main.c), which web/app.js and
 * web/test.js call through Emscripten's cwrap. Every int function returns 0 on success and
 * -1 with tr_web_error() saying why, except tr_web_start and tr_web_meshes_skipped. */
#ifndef TR_WEB_API_H
#define TR_WEB_API_H

#include <stdint.h>

const char *tr_web_error(void);
int tr_web_start(int threads);
const char *tr_web_info(void);
int tr_web_load_builtin(const char *name, int width, int height);
int tr_web_load_file(const char *path, int width, int height);
int tr_web_load_json(const char *name, const char *text, int width, int height);
int tr_web_meshes_skipped(void);
float *tr_web_view(void);
int tr_web_frame(int width, int height, int method, int spp, int moving, double budget_ms,
                 float exposure);
uint8_t *tr_web_pixels(void);
double *tr_web_stats(void);
int tr_web_render(int spp, int seed, int threads);
float *tr_web_image(void);
double tr_web_render_seconds(void);

/* The OpenMP runtime's team (web/omp/omp_runtime.c): starts threads - 1 workers once and
 * returns the team's size. */
int tr_web_omp_start(int threads);

#endif

/* bench.h - helpers shared by the `trac0r bench` benchmarks. */
#ifndef TRAC0R_BENCH_H
#define TRAC0R_BENCH_H

#include "cli.h"

/* The acceleration structures a benchmark compares. */
typedef struct accel_set {
    tr_accel_type type[4];
    int count;
} accel_set;

/* Parses the current option's value, a list such as "bvh,embree". */
int bench_parse_accels(cli_args *a, accel_set *set);
/* Every structure this build has, in the order flat (if with_flat), bvh, embree. */
void bench_accels_all(accel_set *set, int with_flat);
/* Runs a gnuplot script (no file names in it: the PNG comes back on gnuplot's standard
 * output) and writes the plot to `png` through tr_outfile. 1: written; 0: gnuplot is
 * missing or failed (no plot, nothing written); -1: the file could not be written (`err`
 * says why). */
int bench_plot_png(const char *script, const char *png, tr_error *err);
/* The file name of `path` (what follows its last '/') for a plot's title, at most n - 1
 * characters into out, with anything that could end or escape gnuplot's single-quoted
 * string (a quote, a backslash, a control or non-ASCII byte) replaced by '_'. */
void bench_plot_name(const char *path, char *out, size_t n);
/* Appends to the script buf (capacity cap, *len used) what printf would write; once a
 * piece does not fit, *len becomes cap and nothing more is added, so the caller plots
 * only when *len < cap. */
void bench_plot_put(char *buf, size_t cap, size_t *len, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

int bench_rays(int argc, char **argv);
int bench_convergence(int argc, char **argv);
int bench_realtime(int argc, char **argv);

#endif

/* progress.h - progress of a long job on stderr: a bar with the elapsed time and an ETA,
 * redrawn in place while stderr is a terminal; otherwise one line per step, at most one
 * a second (plus the last), so logs of long jobs stay readable. */
#ifndef TRAC0R_PROGRESS_H
#define TRAC0R_PROGRESS_H

#include <stdint.h>

typedef struct progress {
    const char *label; /* "trac0r render", "bench convergence: reference" */
    const char *unit;  /* "spp", "tiles", "scenes" */
    uint64_t total;
    int tty;
    int quiet;       /* prints nothing (MPI ranks other than 0) */
    int drawn;       /* a bar is on the terminal's last line */
    double t0, last; /* start, and the last time a line was printed */
} progress;

/* Starts a job of `total` steps (counted in `unit`). quiet: print nothing. */
void progress_begin(progress *p, const char *label, const char *unit, uint64_t total, int quiet);
/* `done` of the total steps are finished; `extra` (may be NULL) is appended to the line. */
void progress_update(progress *p, uint64_t done, const char *extra);
/* Erases the bar (on a terminal) before other output; the next update redraws it. */
void progress_clear(progress *p);
/* Ends the bar's line on a terminal (before other output follows). */
void progress_end(progress *p);

#endif

/* progress.c - see progress.h. */
#define _POSIX_C_SOURCE 200809L
#include "progress.h"

#include <stdio.h>
#include <unistd.h>

#include "trac0r/render.h"

void progress_begin(progress *p, const char *label, const char *unit, uint64_t total, int quiet) {
    p->label = label;
    p->unit = unit;
    p->total = total;
    p->tty = isatty(fileno(stderr));
    p->quiet = quiet;
    p->drawn = 0;
    p->t0 = tr_time_now();
    p->last = -1.0;
}

static void format_time(char *buf, size_t n, double s) {
    if (s < 0.0) {
        snprintf(buf, n, "?");
    } else if (s < 100.0) {
        snprintf(buf, n, "%.1f s", s);
    } else if (s < 6000.0) {
        snprintf(buf, n, "%dm%02ds", (int)(s / 60.0), (int)s % 60);
    } else {
        snprintf(buf, n, "%dh%02dm", (int)(s / 3600.0), (int)(s / 60.0) % 60);
    }
}

void progress_update(progress *p, uint64_t done, const char *extra) {
    if (p->quiet) {
        return;
    }
    const double now = tr_time_now();
    const int last_step = done >= p->total;
    /* A terminal redraws at most 10 times a second; a log gets a line a second. */
    const double gap = p->tty ? 0.1 : 1.0;
    if (!last_step && p->last >= 0.0 && now - p->last < gap) {
        return;
    }
    p->last = now;
    const double el = now - p->t0;
    const double frac = p->total ? (double)done / (double)p->total : 1.0;
    const double eta = done > 0 ? el / (double)done * (double)(p->total - done) : -1.0;
    char elapsed[32], remain[32];
    format_time(elapsed, sizeof elapsed, el);
    format_time(remain, sizeof remain, eta);
    if (p->tty) {
        char bar[31];
        const int fill = (int)(frac * 30.0);
        for (int i = 0; i < 30; ++i) {
            bar[i] = i < fill ? '#' : '.';
        }
        bar[30] = '\0';
        fprintf(stderr, "\r%s: [%s] %3.0f%% %llu/%llu %s  %s elapsed  ETA %s%s%s\033[K", p->label,
                bar, frac * 100.0, (unsigned long long)done, (unsigned long long)p->total, p->unit,
                elapsed, remain, extra ? "  " : "", extra ? extra : "");
        p->drawn = 1;
    } else {
        fprintf(stderr, "%s: %llu/%llu %s (%.0f%%), %s elapsed, ETA %s%s%s\n", p->label,
                (unsigned long long)done, (unsigned long long)p->total, p->unit, frac * 100.0,
                elapsed, remain, extra ? ", " : "", extra ? extra : "");
    }
    fflush(stderr);
}

void progress_clear(progress *p) {
    if (p->drawn) {
        fputs("\r\033[K", stderr);
        fflush(stderr);
        p->drawn = 0;
        p->last = -1.0; /* redraw at the next update */
    }
}

void progress_end(progress *p) {
    if (p->drawn) {
        fputc('\n', stderr);
        p->drawn = 0;
    }
}

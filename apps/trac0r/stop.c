/* stop.c - see stop.h. */
#define _POSIX_C_SOURCE 200809L
#include "stop.h"

#include <signal.h>
#include <string.h>

static volatile sig_atomic_t stop_signal;
static tr_session *volatile stop_session;
/* The actions the render replaced: a second signal and the end of the render give them
 * back (another part of trac0r may clean up on these signals too). */
static struct sigaction previous_int, previous_term;

static void on_stop(int sig) {
    if (stop_signal) {
        /* Asked twice: do not wait for the pass to end. */
        const struct sigaction *prev = sig == SIGINT ? &previous_int : &previous_term;
        if (prev->sa_handler == SIG_IGN) {
            signal(sig, SIG_DFL);
        } else {
            sigaction(sig, prev, NULL);
        }
        raise(sig);
        return;
    }
    stop_signal = sig;
    if (stop_session) {
        tr_session_cancel(stop_session);
    }
}

void render_stop_install(tr_session *session) {
    stop_session = session;
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_stop;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &previous_int);
    sigaction(SIGTERM, &sa, &previous_term);
}

int render_stop_signal(void) {
    return (int)stop_signal;
}

void render_stop_uninstall(void) {
    sigaction(SIGINT, &previous_int, NULL);
    sigaction(SIGTERM, &previous_term, NULL);
    stop_session = NULL;
}

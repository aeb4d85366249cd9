/* stop.h - SIGINT and SIGTERM during `trac0r render`: the first one asks the session to
 * stop at the end of the pass under way (tr_session_cancel, one atomic store); a second
 * one gets the action installed before (the default one where it was ignored) and is
 * raised again, so the process ends without waiting for the pass. The library installs no
 * handlers of its own. */
#ifndef TRAC0R_STOP_H
#define TRAC0R_STOP_H

#include "trac0r/session.h"

/* Installs the handlers; a signal cancels `session` (NULL: only noted). */
void render_stop_install(tr_session *session);
/* The signal that asked the render to stop, or 0. */
int render_stop_signal(void);
/* Restores the actions installed before. */
void render_stop_uninstall(void);

#endif

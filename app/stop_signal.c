/* stop_signal.c — the stop request of `bigstep run` (app.h): SIGINT and
 * SIGTERM set a flag that the run reads between Newton iterations. */
#include <signal.h>
#include <string.h>

#include "app.h"

volatile sig_atomic_t bs_app_stop_signal = 0;

static void on_stop_signal(int sig) { bs_app_stop_signal = sig; }

/* The handlers only set the flag; SA_RESETHAND puts the default back, so a
 * second Ctrl-C ends the program at once. */
void bs_app_install_stop_handlers(void) {
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESETHAND | SA_RESTART; /* no EINTR from a write to a pipe or terminal */
  sigaction(SIGINT, &sa, NULL);
  sigaction(SIGTERM, &sa, NULL);
}

const char *bs_app_signal_name(int sig) { return sig == SIGTERM ? "SIGTERM" : "SIGINT"; }

int bs_app_stop_status(int sig) { return 128 + (sig == SIGTERM ? SIGTERM : SIGINT); }

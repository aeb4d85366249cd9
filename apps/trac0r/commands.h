/* commands.h - the trac0r subcommands; each returns the process exit status. */
#ifndef TRAC0R_COMMANDS_H
#define TRAC0R_COMMANDS_H

int cmd_render(int argc, char **argv);
int cmd_bench(int argc, char **argv);
int cmd_info(int argc, char **argv);

#endif

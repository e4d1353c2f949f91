/* commands.h: one entry point per lissom-sim subcommand (argv[0] is the first argument after it). */
#ifndef LSM_SIM_COMMANDS_H
#define LSM_SIM_COMMANDS_H

int cmd_version(int argc, char **argv);
int cmd_scurve(int argc, char **argv);
int cmd_move(int argc, char **argv);
int cmd_demo(int argc, char **argv);
int cmd_bench(int argc, char **argv);
int cmd_experiment(int argc, char **argv);
int cmd_clothoid(int argc, char **argv);
int cmd_smooth(int argc, char **argv);
int cmd_bench_clothoid(int argc, char **argv);
int cmd_run(int argc, char **argv);
int cmd_bench_planner(int argc, char **argv);
int cmd_plot(int argc, char **argv);
int cmd_check(int argc, char **argv);
int cmd_stream(int argc, char **argv);
/* further subcommands declare here, one line each */

#endif

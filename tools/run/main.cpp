// stabint-run's executable: the tool is runCli (run.cpp), which Python's `stabint-run` command
// calls too.
#include "cli.hpp"

int main(int argc, char** argv) { return stabint_run::runCli(argc, argv); }

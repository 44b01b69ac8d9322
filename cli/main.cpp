#include "cli/commands.h"

int main(int argc, char** argv) { return prtsub::run_cli(argc, argv); }

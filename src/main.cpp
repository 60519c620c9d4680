#include "cli/commands.hpp"

int main(int argc, char** argv) { return mbstorm::cli::run_cli(argc, argv); }

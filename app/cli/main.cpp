#include "app/cli/cli_support.hpp"

int main(int argc, char** argv) { return flexirob::cli::runCli(argc, argv); }

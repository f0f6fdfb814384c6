// Placeholder registration while the owning module is being built.
#include "app/cli/cli_support.hpp"
namespace flexirob::cli {
void registerItmCommands(CLI::App&, CommandRunner&) {}
}  // namespace flexirob::cli

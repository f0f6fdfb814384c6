// Placeholder registration while the owning module is being built.
#include "app/cli/cli_support.hpp"
namespace flexirob::cli {
void registerLearnCommands(CLI::App&, CommandRunner&) {}
}  // namespace flexirob::cli

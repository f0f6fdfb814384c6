#pragma once
// Strict parsing of the numeric lists users type on the command line ("0.1,-0.2,3e-2").
// Kept apart from the rest of the CLI so that the fuzz target (fuzz/number_list_fuzzer.cpp)
// builds it without the commands.
#include <Eigen/Core>
#include <cstddef>
#include <string>

namespace flexirob::cli {

/// Parses "1.0,2,-3e-2" strictly: every entry a finite number, no empty entries, at most
/// max_count entries. Throws InputError naming `what`; the message quotes at most a short
/// excerpt of the text, so a huge argument still yields a one-line error.
Eigen::VectorXd parseNumberList(const std::string& text, const std::string& what,
                                std::size_t max_count = 4096);
/// As parseNumberList with exactly `count` entries.
Eigen::VectorXd parseNumberList(const std::string& text, const std::string& what, int count);

}  // namespace flexirob::cli

#pragma once

#include <CLI/CLI.hpp>

#include <optional>
#include <string>

namespace rise::cli {

/// The exit code of every program when its command line is wrong (README,
/// "Programs"): 0 ok, 1 the program ran and the answer is no, 2 bad input.
inline constexpr int kBadInput = 2;

/// Names the program, adds --version ("rise-hild 0.1.0 (f28b7cb)") and
/// parses argv. Returns std::nullopt when the program should go on, else
/// the code main() returns: 0 after --help or --version, a subcommand
/// callback's own code (CLI::RuntimeError), kBadInput for any other error
/// (printed by CLI11 on stderr).
std::optional<int> parse_command_line(CLI::App& app, const std::string& program, int argc, char** argv);

}  // namespace rise::cli

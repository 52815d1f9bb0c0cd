// libFuzzer target: arbitrary command lines through tridiff::cli::check_command_line, which
// parses and checks a whole `tridiff` command line as main() does, without reading inputs,
// doing the work or writing anything.
//
// Input layout: argv[1..] separated by '\0' or '\n' (argv[0] is "tridiff"). A bad command line
// is refused with tridiff::Error; anything else is a finding: a crash, a sanitizer report or
// another exception (std::out_of_range from a number parser, say).
#include <cstdint>
#include <string>
#include <vector>

#include "common.hpp"
#include "tridiff/solvers/error.hpp"

namespace {

std::vector<std::string> split_arguments(const std::uint8_t* data, std::size_t size) {
  std::vector<std::string> tokens{"tridiff"};
  std::string token;
  for (std::size_t k = 0; k < size; ++k) {
    const char c = static_cast<char>(data[k]);
    if (c == '\0' || c == '\n') {
      tokens.push_back(token);
      token.clear();
    } else {
      token += c;
    }
  }
  if (!token.empty()) tokens.push_back(token);
  return tokens;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::string> tokens = split_arguments(data, size);
  // main()'s argv: writable strings and a null pointer after the last.
  std::vector<char*> argv;
  for (std::string& token : tokens) argv.push_back(token.data());
  argv.push_back(nullptr);
  try {
    tridiff::cli::check_command_line(static_cast<int>(tokens.size()), argv.data());
  } catch (const tridiff::Error&) {
    // Refused: allowed.
  }
  return 0;
}

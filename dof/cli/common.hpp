// What the subcommands of `tridiff` share: option parsing and loading a frame (colour, depth
// and the CoC map, from files or the built-in scene) from the same image and lens options.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "tridiff/image/image.hpp"

namespace tridiff::cli {

struct Arguments {
  std::map<std::string, std::string> values;
  std::vector<std::string> flags;
  bool has(const std::string& key) const { return values.count(key) != 0; }
  bool flag(const std::string& key) const;
  std::string text(const std::string& key, const std::string& fallback) const;
  // InvalidArgument naming --key when the value is not a (finite) number / an integer.
  float number(const std::string& key, float fallback) const;
  int integer(const std::string& key, int fallback) const;
};

// The options that choose and read the frame and its CoC (see kInputUsage).
extern const std::vector<std::string> kInputOptions;
extern const char* const kInputUsage;

// Parses argv[first..]: `flags` take no value, `valued` take one; anything else is an error.
Arguments parse(int argc, char** argv, int first, const std::vector<std::string>& flags,
                const std::vector<std::string>& valued);

struct Frame {
  Image color, depth, coc;  // coc: signed diameter, pixels
  std::string source;       // what was read, for the summary
  std::string coc_model;    // the lens or curve used
  double load_seconds = 0, coc_seconds = 0;
};

// The colour and depth files of --color/--depth, or the built-in scene, and its CoC map.
Frame load_frame(const Arguments& args, int threads);

// The `ipf` subcommand (ipf_command.cpp).
extern const char* const kIpfUsage;
int run_ipf(const Arguments& args);
extern const std::vector<std::string> kIpfFlags, kIpfValued;

}  // namespace tridiff::cli

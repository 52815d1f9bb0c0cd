// What the subcommands of `tridiff` share: option parsing and loading a frame (colour, depth
// and the CoC map, from files or the built-in scene) from the same image and lens options.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "tridiff/image/image.hpp"
#include "tridiff/image/output_files.hpp"

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

// Parses argv[first..]: `flags` take no value, `valued` take one; anything else is an error,
// and so is an option or flag given twice (-o and --output are one option).
Arguments parse(int argc, char** argv, int first, const std::vector<std::string>& flags,
                const std::vector<std::string>& valued);

struct Frame {
  Image color, depth, coc;  // coc: signed diameter, pixels
  std::string source;       // what was read, for the summary
  std::string coc_model;    // the lens or curve used
  // The thin lens as a photographer says it ("50 mm f/2.8 focused at 3.2 m, sensor 36 mm";
  // empty with the artist curve), and with --color the lens options left at tridiff's
  // defaults (focus, focal-length, f-number, sensor-width), which are not the user's camera.
  std::string lens;
  std::vector<std::string> lens_defaults;
  double load_seconds = 0, coc_seconds = 0;
};

// The colour and depth files of --color/--depth, or the built-in scene, and its CoC map.
// Calls check_input_options first.
Frame load_frame(const Arguments& args, int threads);

// The input and lens options that cannot go together, checked before anything is read:
// --width/--height with --color, a lens option with an artist-curve option, and the artist
// curve itself (e.g. an empty or reversed near range); InvalidArgument naming the option(s).
void check_input_options(const Arguments& args);

// The library names a parameter by its field (f_number, register_size); the user typed an option
// (--f-number). The one translation between them, at the command line's edge: runs `work`, and
// an InvalidArgument naming the field of one of `options` (kebab-case, without "--"; `aliases`
// maps other field names to options) is thrown again naming "--option", with the field names of
// `options` in its message renamed the same way. Any other error passes through unchanged.
void with_fields_as_options(const std::vector<std::string>& options,
                            const std::function<void()>& work,
                            const std::vector<std::pair<std::string, std::string>>& aliases = {});

// Runs `work` (a method on the frame's CoC map); a method's InvalidArgument about the map
// ("coc": too large for it) is named as the options that made it (--max-coc, or the artist
// curve's --near-radius/--far-radius).
void with_coc_named(const Arguments& args, const std::function<void()>& work);

// A whole command line: the subcommand (dof, ipf, methods or --help) and its arguments.
struct CommandLine {
  std::string command;
  Arguments args;
};

// InvalidArgument naming the argument at fault when the command line cannot be parsed.
CommandLine parse_command_line(int argc, char** argv);

// Parses and checks a command line as run_command_line would before its work: the options,
// their values and the output paths. Reads no input, does no work, writes nothing; throws a
// tridiff::Error at the first fault.
void check_command_line(int argc, char** argv);

// Runs the command line; the exit status (errors are thrown).
int run_command_line(int argc, char** argv);

// --threads: 0 (all cores) up to the library's bound, or InvalidArgument naming --threads.
int thread_count(const Arguments& args);

// --max-pixels: the largest input image read (default: the library's 16384 x 16384).
std::int64_t max_pixels(const Arguments& args);

// Registers the --color and --depth files with `files`: no output may replace them.
void register_inputs(const Arguments& args, OutputFiles& files);

// One output file's bytes to make: the option that names it, and its encoder, given the
// threads it may use.
struct Encoding {
  std::string label;
  std::function<std::vector<unsigned char>(int threads)> encode;
};

// Encodes the outputs side by side, as many at once as `threads` allows (PNG's zlib is
// serial; OpenEXR compresses on its own thread pool, whatever `threads` says), then stages
// them with `files` in their order. The first failure in that order is thrown, and nothing
// after it is staged. On one thread, each is staged before the next is made.
void encode_and_stage(const std::vector<Encoding>& encodings, int threads, OutputFiles& files);

// The `ipf` subcommand (ipf_command.cpp).
extern const char* const kIpfUsage;
int run_ipf(const Arguments& args);
// Checks an `ipf` command line's options and output as run_ipf does before its work.
void check_ipf(const Arguments& args);
extern const std::vector<std::string> kIpfFlags, kIpfValued;

}  // namespace tridiff::cli

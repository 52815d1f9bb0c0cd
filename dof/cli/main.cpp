// The `tridiff` command: every error ends as one line on stderr and a non-zero exit.
#include <csignal>
#include <cstdio>
#include <exception>
#include <new>

#include "common.hpp"
#include "tridiff/image/output_files.hpp"

int main(int argc, char** argv) {
  // Ctrl-C while outputs are written leaves none of their temporary files behind.
  tridiff::OutputFiles::remove_temporaries_on_signal();
  // Past the file-size limit a write fails with EFBIG, an error tridiff reports naming the
  // file, rather than the signal ending the process.
  std::signal(SIGXFSZ, SIG_IGN);
  try {
    return tridiff::cli::run_command_line(argc, argv);
  } catch (const std::bad_alloc&) {
    std::fputs(
        "tridiff: not enough memory for this frame and method (try a smaller image, "
        "fewer --threads or another --method)\n",
        stderr);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "%s\n", error.what());
  }
  return 1;
}

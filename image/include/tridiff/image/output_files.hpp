// The files a program writes, as one set: every path checked before the work, each file
// written whole or not at all, and the set replaced all or nothing.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "tridiff/image/io.hpp"

namespace tridiff {

// Outputs are regular files. A path that names a folder, a device, a FIFO or a socket, or the
// file this process's standard input, output or error is attached to, is refused: every
// output is written to a new file beside its target and renamed over it, which would replace
// the node itself (run as root, `/dev/null` would become a regular file for the whole
// machine) or leave the shell's redirection writing into a file no longer in the folder.
//
//   OutputFiles files;
//   files.input("--color", color_path);          // no output may replace an input
//   files.claim("--output", output_path);        // before the work: checked, nothing created
//   ... the work ...
//   files.stage("--output", encode_image(output_path, result));
//   files.commit();                              // every file renamed into place, or none
//
// stage() writes to a temporary file in the target's folder with checked writes and fsync,
// so a full disk or a failing device is an error naming the file, never a truncated output.
// commit() keeps a hard link to each file it replaces until all renames succeeded and puts
// them back if one fails. The destructor removes temporaries that were not committed.
// Errors are ImageIoError, beginning "tridiff: <label> '<path>': ".
class OutputFiles {
 public:
  OutputFiles() = default;
  OutputFiles(const OutputFiles&) = delete;
  OutputFiles& operator=(const OutputFiles&) = delete;
  OutputFiles(OutputFiles&& other) noexcept;
  OutputFiles& operator=(OutputFiles&& other) noexcept;  // removes this set's temporaries
  ~OutputFiles();

  // Records an input file: no claimed output may be the same file (compared by device and
  // inode, so another spelling, a symbolic or a hard link is caught). A path that cannot be
  // examined is ignored here: reading it will say why.
  void input(const std::string& label, const std::string& path);

  // Checks `path` as the output called `label`, touching nothing on disk: not empty, not
  // too long, in an existing folder this process may write in, not a folder or special file
  // (see above), not an input, not claimed before under any spelling.
  void claim(const std::string& label, const std::string& path);

  // Writes the file claimed as `label` to its temporary file (replacing what was staged).
  void stage(const std::string& label, std::string_view bytes);
  void stage(const std::string& label, const std::vector<unsigned char>& bytes);

  // Renames every staged file over its target; if one rename fails, the files already
  // replaced get their previous content back (or are removed when they were new) and the
  // error names the file that failed. Claimed files that were never staged are skipped.
  void commit();

  // Installs handlers for SIGINT, SIGTERM and SIGHUP that remove the temporary files of every
  // OutputFiles in the process, then end it as the signal would have. A signal that arrives
  // during commit() is held until the renames are done. For programs, not libraries: call it
  // once from main().
  static void remove_temporaries_on_signal();

 private:
  struct FileId {
    std::uint64_t device = 0, inode = 0;
    bool operator==(const FileId&) const = default;
  };
  struct Input {
    std::string label;
    FileId id;
  };
  struct Output {
    std::string label, path;  // as given
    std::string target;       // the file to replace: symbolic links resolved
    bool exists = false;      // at claim time
    FileId id;                // when it exists
    unsigned mode = 0;        // its permissions, when it exists: the new file keeps them
    std::string temporary;    // when staged
    int slot = -1;            // in the signal handler's registry
  };

  [[noreturn]] static void fail(const Output& output, const std::string& why);
  Output& find(const std::string& label);
  void remove_temporary(Output& output);

  std::vector<Input> inputs_;
  std::vector<Output> outputs_;
};

}  // namespace tridiff

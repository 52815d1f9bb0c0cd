// Output files written whole, replaced as a set, and never over a device, an input or the
// terminal's redirection: see output_files.hpp for the policy.
#include "tridiff/image/output_files.hpp"

#include <fcntl.h>
#include <limits.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace tridiff {
namespace {

namespace fs = std::filesystem;

std::string describe_errno(int error) { return std::strerror(error); }

// What a special file is, for the message that refuses it.
std::string kind_of(mode_t mode) {
  if (S_ISCHR(mode)) return "character device";
  if (S_ISBLK(mode)) return "block device";
  if (S_ISFIFO(mode)) return "FIFO (named pipe)";
  if (S_ISSOCK(mode)) return "socket";
  return "special file";
}

// ---------------------------------------------------------------------------------------------
// The temporaries a signal handler may have to remove. A handler may only touch lock-free
// atomics and call async-signal-safe functions (unlink, signal, raise), so the registry is a
// fixed array of paths, each slot published by its state: free -> writing -> ready.

constexpr int kSlots = 64;
enum SlotState { kFree = 0, kWriting = 1, kReady = 2 };
struct Slot {
  std::atomic<int> state{kFree};
  char path[PATH_MAX];
};
Slot g_slots[kSlots];
std::atomic<int> g_committing{0};      // commits in progress, in any thread
std::atomic<int> g_pending_signal{0};  // a signal held until they finish
static_assert(std::atomic<int>::is_always_lock_free);

// -1 when the registry is full or the path too long: the file is then still removed by its
// owner, only not by a signal handler.
int register_temporary(const std::string& path) {
  if (path.size() >= PATH_MAX) return -1;
  for (int i = 0; i < kSlots; ++i) {
    int expected = kFree;
    if (!g_slots[i].state.compare_exchange_strong(expected, kWriting)) continue;
    std::memcpy(g_slots[i].path, path.c_str(), path.size() + 1);
    g_slots[i].state.store(kReady);
    return i;
  }
  return -1;
}

void unregister_temporary(int slot) {
  if (slot >= 0) g_slots[slot].state.store(kFree);
}

void remove_registered_temporaries() {
  for (Slot& slot : g_slots)
    if (slot.state.load() == kReady) ::unlink(slot.path);
}

void end_by_signal(int signal_number) {
  remove_registered_temporaries();
  std::signal(signal_number, SIG_DFL);
  std::raise(signal_number);
}

extern "C" void on_signal(int signal_number) {
  if (g_committing.load() > 0) {
    g_pending_signal.store(signal_number);
    return;
  }
  end_by_signal(signal_number);
}

// Holds signals for the length of a commit; delivers one that arrived once the last commit
// in progress ends.
class CommitGuard {
 public:
  CommitGuard() { g_committing.fetch_add(1); }
  CommitGuard(const CommitGuard&) = delete;
  CommitGuard& operator=(const CommitGuard&) = delete;
  ~CommitGuard() {
    if (g_committing.fetch_sub(1) == 1)
      if (const int held = g_pending_signal.exchange(0)) end_by_signal(held);
  }
};

// A name in `folder` that no other writer uses, short whatever the target's name: a target
// name near the file-name limit must not make its temporary's name too long.
std::string scratch_name(const fs::path& folder, const char* suffix) {
  static std::atomic<unsigned long> counter{0};
  return (folder / (".tridiff-" + std::to_string(::getpid()) + "-" +
                    std::to_string(counter.fetch_add(1)) + suffix))
      .string();
}

// Writes all of `bytes` to `fd` and flushes them to the device: the errors of a full disk
// may only show at fsync (delayed allocation, network file systems). 0 or an errno value.
int write_all(int fd, std::string_view bytes) {
  const char* next = bytes.data();
  std::size_t left = bytes.size();
  while (left > 0) {
    const ssize_t written = ::write(fd, next, left);
    if (written < 0) {
      if (errno == EINTR) continue;
      return errno;
    }
    next += written;
    left -= static_cast<std::size_t>(written);
  }
  return ::fsync(fd) == 0 ? 0 : errno;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

OutputFiles::~OutputFiles() {
  for (Output& output : outputs_) remove_temporary(output);
}

OutputFiles::OutputFiles(OutputFiles&& other) noexcept
    : inputs_(std::move(other.inputs_)), outputs_(std::move(other.outputs_)) {
  other.outputs_.clear();
}

OutputFiles& OutputFiles::operator=(OutputFiles&& other) noexcept {
  if (this == &other) return *this;
  for (Output& output : outputs_) remove_temporary(output);  // what this set staged goes
  inputs_ = std::move(other.inputs_);
  outputs_ = std::move(other.outputs_);
  other.outputs_.clear();
  return *this;
}

void OutputFiles::fail(const Output& output, const std::string& why) {
  const std::string where =
      output.label.empty() ? output.path : output.label + " '" + output.path + "'";
  throw ImageIoError("tridiff: " + where + ": " + why);
}

OutputFiles::Output& OutputFiles::find(const std::string& label) {
  for (Output& output : outputs_)
    if (output.label == label) return output;
  throw std::logic_error("OutputFiles: '" + label + "' was not claimed");
}

void OutputFiles::input(const std::string& label, const std::string& path) {
  struct stat status;
  if (::stat(path.c_str(), &status) != 0) return;
  const FileId id{status.st_dev, status.st_ino};
  for (const Output& output : outputs_)
    if (output.exists && output.id == id)
      fail(output, "is the " + label + " file: an output may not replace an input");
  inputs_.push_back({label, id});
}

void OutputFiles::claim(const std::string& label, const std::string& path) {
  for (const Output& output : outputs_)
    if (output.label == label) throw std::logic_error("OutputFiles: '" + label + "' claimed twice");
  Output output;
  output.label = label;
  output.path = path;
  if (path.empty()) fail(output, "the path is empty");

  struct stat status;
  if (::stat(path.c_str(), &status) == 0) {
    output.exists = true;
    output.id = {status.st_dev, status.st_ino};
    output.mode = status.st_mode & 07777;
    if (S_ISDIR(status.st_mode)) fail(output, "is a folder");
    if (!S_ISREG(status.st_mode))
      fail(output, "is a " + kind_of(status.st_mode) +
                       ", not a regular file (outputs are written to a new file and renamed "
                       "into place, which would replace it)");
    const char* const stream_names[] = {"input", "output", "error"};
    for (int fd = 0; fd < 3; ++fd) {
      struct stat stream;
      if (::fstat(fd, &stream) == 0 && FileId{stream.st_dev, stream.st_ino} == output.id)
        fail(output, std::string("is the file this program's standard ") + stream_names[fd] +
                         " is attached to (renaming a new file over it would cut the "
                         "redirection off)");
    }
    for (const Input& input : inputs_)
      if (input.id == output.id)
        fail(output, "is the " + input.label + " file: an output may not replace an input");
  } else if (errno == ENAMETOOLONG) {
    fail(output, "the name is too long for the file system");
  } else if (errno == ENOTDIR) {
    fail(output, "a part of the path before the file name is not a folder");
  } else if (errno != ENOENT) {
    fail(output, "cannot examine it (" + describe_errno(errno) + ")");
  }

  // Replace the file a symbolic link points at, not the link.
  std::error_code error;
  const fs::path target = fs::weakly_canonical(fs::absolute(path), error);
  if (error) fail(output, "cannot resolve the path (" + error.message() + ")");
  const fs::path folder = target.parent_path();
  if (!fs::is_directory(folder, error))
    fail(output, "the folder '" + folder.string() + "' does not exist");
  if (::access(folder.c_str(), W_OK | X_OK) != 0)
    fail(output,
         "cannot write in the folder '" + folder.string() + "' (" + describe_errno(errno) + ")");
  output.target = target.string();
  for (const Output& other : outputs_)
    if (other.target == output.target || (other.exists && output.exists && other.id == output.id))
      fail(output, "is also the " + (other.label.empty() ? "other output" : other.label) + " file");
  outputs_.push_back(std::move(output));
}

void OutputFiles::stage(const std::string& label, const std::vector<unsigned char>& bytes) {
  stage(label, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

void OutputFiles::stage(const std::string& label, std::string_view bytes) {
  Output& output = find(label);
  remove_temporary(output);
  output.temporary = scratch_name(fs::path(output.target).parent_path(), ".partial");
  output.slot = register_temporary(output.temporary);
  const int fd = ::open(output.temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd < 0) {
    const int error = errno;
    unregister_temporary(output.slot);
    output.slot = -1;
    output.temporary.clear();
    fail(output, "cannot create a file in its folder (" + describe_errno(error) + ")");
  }
  // A replaced file keeps its permissions.
  int error = output.exists && ::fchmod(fd, output.mode) != 0 ? errno : 0;
  if (!error) error = write_all(fd, bytes);
  if (::close(fd) != 0 && !error) error = errno;
  if (error) {
    remove_temporary(output);
    fail(output, "cannot write (" + describe_errno(error) + "); the file was left as it was");
  }
}

void OutputFiles::remove_temporary(Output& output) {
  if (output.temporary.empty()) return;
  ::unlink(output.temporary.c_str());
  unregister_temporary(output.slot);
  output.slot = -1;
  output.temporary.clear();
}

void OutputFiles::commit() {
  const CommitGuard hold_signals;
  // What commit did to each target, to undo it if a later one fails.
  struct Step {
    std::string backup;    // the replaced file, kept under another name until all succeeded
    bool moved = false;    // kept by rename (no hard links on this file system), not a link
    bool renamed = false;  // the new file is in place
  };
  std::vector<Step> steps(outputs_.size());
  const auto undo = [&](std::size_t count) {
    for (std::size_t j = 0; j < count; ++j) {
      const Step& step = steps[j];
      const char* target = outputs_[j].target.c_str();
      if (!step.backup.empty() && (step.renamed || step.moved))
        ::rename(step.backup.c_str(), target);  // the previous content back
      else if (!step.backup.empty())
        ::unlink(step.backup.c_str());
      else if (step.renamed)
        ::unlink(target);  // it was new
    }
  };
  for (std::size_t i = 0; i < outputs_.size(); ++i) {
    Output& output = outputs_[i];
    Step& step = steps[i];
    if (output.temporary.empty()) continue;
    std::string error;
    struct stat status;
    if (::lstat(output.target.c_str(), &status) == 0) {
      if (!S_ISREG(status.st_mode)) {
        // Something else took the name since claim(): never move it aside or replace it.
        error = S_ISDIR(status.st_mode) ? "it is a folder now"
                                        : "it is a " + kind_of(status.st_mode) + " now";
      } else {
        step.backup = scratch_name(fs::path(output.target).parent_path(), ".old");
        if (::link(output.target.c_str(), step.backup.c_str()) != 0) {
          // A file system without hard links: move the file aside instead.
          if (::rename(output.target.c_str(), step.backup.c_str()) == 0)
            step.moved = true;
          else
            error = describe_errno(errno), step.backup.clear();
        }
      }
    }
    if (error.empty() && ::rename(output.temporary.c_str(), output.target.c_str()) != 0)
      error = describe_errno(errno);
    if (!error.empty()) {
      undo(i + 1);
      fail(output, "cannot replace the file (" + error + "); no output of this run was changed");
    }
    step.renamed = true;
    unregister_temporary(output.slot);
    output.slot = -1;
    output.temporary.clear();
  }
  for (const Step& step : steps)
    if (!step.backup.empty()) ::unlink(step.backup.c_str());
}

void OutputFiles::remove_temporaries_on_signal() {
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  for (const int signal_number : {SIGINT, SIGTERM, SIGHUP})
    ::sigaction(signal_number, &action, nullptr);
}

}  // namespace tridiff

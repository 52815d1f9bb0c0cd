// OutputFiles, the policy of every file tridiff writes: checked before the work, never over a
// special file, an input or a redirected standard stream, a failed write (a full disk) an
// error that changes nothing, a set replaced all or nothing, no temporary left by a signal.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <set>
#include <string>

#include "tridiff/image/output_files.hpp"
#include "test_util.hpp"

namespace tridiff::test {
namespace {

using namespace tridiff::testing_util;
namespace fs = std::filesystem;

std::string message_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const ImageIoError& error) {
    return error.what();
  }
  ADD_FAILURE() << "no ImageIoError thrown";
  return {};
}

class OutputFilesTest : public ScratchFolderTest {
 protected:
  void put(const std::string& name, const std::string& text) const {
    std::ofstream(file(name), std::ios::binary) << text;
  }
  std::string get(const std::string& name) const {
    std::ifstream in(file(name), std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
  }
};

TEST_F(OutputFilesTest, WritesAndReplacesWholeKeepingPermissions) {
  put("old.txt", "previous");
  ::chmod(file("old.txt").c_str(), 0640);
  OutputFiles files;
  files.claim("--a", file("new.txt"));
  files.claim("--b", file("old.txt"));
  files.stage("--a", "alpha");
  files.stage("--b", "beta");
  EXPECT_EQ(get("old.txt"), "previous");  // nothing changes before commit
  files.commit();
  EXPECT_EQ(get("new.txt"), "alpha");
  EXPECT_EQ(get("old.txt"), "beta");
  EXPECT_EQ(fs::status(file("old.txt")).permissions() & fs::perms::all,
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  EXPECT_EQ(listing(), (std::set<std::string>{"new.txt", "old.txt"}));
}

TEST_F(OutputFilesTest, SpecialFilesAreRefusedAndLeftAsTheyAre) {
  ASSERT_EQ(::mkfifo(file("pipe").c_str(), 0600), 0);
  OutputFiles files;
  EXPECT_TRUE(
      contains(message_of([&] { files.claim("--report", file("pipe")); }),
               "--report '" + file("pipe") + "': is a FIFO (named pipe), not a regular file"));
  EXPECT_TRUE(contains(message_of([&] { files.claim("--report", "/dev/null"); }),
                       "'/dev/null': is a character device"));
  EXPECT_TRUE(
      contains(message_of([&] { files.claim("--output", folder_.string()); }), "is a folder"));
  EXPECT_TRUE(fs::is_fifo(file("pipe")));
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
  EXPECT_EQ(listing(), (std::set<std::string>{"pipe"}));
}

// `--report /dev/stdout > file`: the path resolves to a regular file, the one the shell
// opened; renaming over it would cut the redirection off. Tested on standard input (swapping
// standard output would hide the test's own report).
TEST_F(OutputFilesTest, TheFileOfAStandardStreamIsRefused) {
  put("redirected.txt", "x");
  const int saved = ::dup(0);
  const int fd = ::open(file("redirected.txt").c_str(), O_RDONLY);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::dup2(fd, 0), 0);
  OutputFiles files;
  const std::string message = message_of([&] { files.claim("--report", "/dev/stdin"); });
  ::dup2(saved, 0);
  ::close(saved);
  ::close(fd);
  EXPECT_TRUE(contains(message, "standard input"));
  EXPECT_EQ(get("redirected.txt"), "x");
}

TEST_F(OutputFilesTest, AnInputIsNeverAnOutputUnderAnySpelling) {
  put("color.png", "pixels");
  fs::create_hard_link(file("color.png"), file("hard.png"));
  fs::create_symlink(file("color.png"), file("soft.png"));
  OutputFiles files;
  files.input("--color", file("color.png"));
  for (const char* name : {"color.png", "hard.png", "soft.png", "./color.png"})
    EXPECT_TRUE(contains(message_of([&] { files.claim("--output", file(name)); }),
                         "is the --color file: an output may not replace an input"))
        << name;
  // Claimed first, registered as an input after: refused all the same.
  OutputFiles later;
  later.claim("--coc-output", file("hard.png"));
  EXPECT_TRUE(contains(message_of([&] { later.input("--depth", file("color.png")); }),
                       "is the --depth file"));
  EXPECT_EQ(get("color.png"), "pixels");
}

TEST_F(OutputFilesTest, OneFileClaimedTwiceIsRefused) {
  put("a.png", "a");
  fs::create_hard_link(file("a.png"), file("b.png"));
  OutputFiles files;
  files.claim("--output", file("a.png"));
  EXPECT_TRUE(contains(message_of([&] { files.claim("--coc-output", file("b.png")); }),
                       "is also the --output file"));
  EXPECT_TRUE(contains(message_of([&] { files.claim("--report", folder_.string() + "/./a.png"); }),
                       "is also the --output file"));
}

TEST_F(OutputFilesTest, NamesAtAndBeyondTheFileNameLimit) {
  // 255 bytes is the usual limit of one name: the longest legal name works (the temporary's
  // name does not grow with it), one byte more is refused as too long, before any work.
  const std::string longest = std::string(251, 'n') + ".png";
  OutputFiles files;
  files.claim("--output", file(longest));
  files.stage("--output", "ok");
  files.commit();
  EXPECT_EQ(get(longest), "ok");
  OutputFiles more;
  EXPECT_TRUE(contains(message_of([&] { more.claim("--output", file("n" + longest)); }),
                       "the name is too long"));
  EXPECT_TRUE(contains(message_of([&] { more.claim("--output", file("no/such/folder/x.png")); }),
                       "does not exist"));
  put("plain", "");
  EXPECT_TRUE(contains(message_of([&] { more.claim("--output", file("plain/x.png")); }),
                       "is not a folder"));
  EXPECT_TRUE(contains(message_of([&] { more.claim("--output", ""); }), "the path is empty"));
}

// A write that fails (here past the file-size limit, as a full disk fails it) is an error
// naming the file and the reason; the old file and the folder are as they were.
TEST_F(OutputFilesTest, AFailedWriteChangesNothing) {
  put("keep.bin", "old content");
  OutputFiles files;
  files.claim("--output", file("keep.bin"));
  files.claim("--report", file("fresh.json"));
  files.stage("--report", "{}");

  struct rlimit saved;
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &saved), 0);
  const auto old_handler = ::signal(SIGXFSZ, SIG_IGN);  // else the signal ends the process
  struct rlimit small = saved;
  small.rlim_cur = 4096;
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
  const std::string message =
      message_of([&] { files.stage("--output", std::string(100000, 'x')); });
  ::setrlimit(RLIMIT_FSIZE, &saved);
  ::signal(SIGXFSZ, old_handler);

  EXPECT_TRUE(
      contains(message, "--output '" + file("keep.bin") + "': cannot write (File too large)"));
  EXPECT_EQ(get("keep.bin"), "old content");
  files = OutputFiles();  // the run gives up: its staged report goes too
  EXPECT_EQ(listing(), (std::set<std::string>{"keep.bin"}));
}

// If a rename fails half-way, the files already replaced get their old content back, new
// ones are removed, and nothing of the run stays in the folder.
TEST_F(OutputFilesTest, AFailedCommitRestoresTheFilesAlreadyReplaced) {
  put("first.png", "first, old");
  put("third.png", "third, old");
  OutputFiles files;
  files.claim("--first", file("first.png"));
  files.claim("--second", file("second.png"));
  files.claim("--third", file("third.png"));
  files.stage("--first", "first, new");
  files.stage("--second", "second, new");
  files.stage("--third", "third, new");
  // Something takes the third name after the checks: a folder with a file in it.
  fs::remove(file("third.png"));
  fs::create_directories(file("third.png/inside"));
  const std::string message = message_of([&] { files.commit(); });
  EXPECT_TRUE(contains(message, "--third '" + file("third.png") + "': cannot replace the file"));
  EXPECT_TRUE(contains(message, "no output of this run was changed"));
  EXPECT_EQ(get("first.png"), "first, old");
  EXPECT_FALSE(fs::exists(file("second.png")));
  files = OutputFiles();
  EXPECT_EQ(listing(), (std::set<std::string>{"first.png", "third.png"}));
}

// Ctrl-C while a file is staged: the handler removes the temporary and the process ends by
// the signal, as it would have without the handler.
TEST_F(OutputFilesTest, ASignalRemovesTheTemporaries) {
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    OutputFiles::remove_temporaries_on_signal();
    OutputFiles files;
    files.claim("--output", file("out.png"));
    files.stage("--output", "staged, never committed");
    ::raise(SIGINT);
    ::_exit(0);  // not reached
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGINT) << status;
  EXPECT_TRUE(listing().empty());
}

}  // namespace
}  // namespace tridiff::test

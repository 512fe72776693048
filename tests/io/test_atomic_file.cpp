#include "io/atomic_file.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include "core/error.hpp"
#include "temp_dir.hpp"

namespace cisamr::io {
namespace {

using testing::read_text;
using testing::TempDir;

TEST(AtomicFile, CommitRenamesAndLeavesNoTemporary) {
  TempDir dir;
  const std::string path = dir.file("out.txt");
  {
    AtomicFile file(path);
    file.write("hello ");
    EXPECT_FALSE(std::filesystem::exists(path)) << "destination must not appear before commit";
    EXPECT_TRUE(std::filesystem::exists(file.temporary_path()));
    EXPECT_EQ(std::filesystem::path(file.temporary_path()).parent_path(), dir.path());
    const std::string big(3 << 20, 'x');  // larger than the internal buffer
    file.write(big);
    file.write("!");
    file.commit();
    EXPECT_TRUE(file.committed());
  }
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.txt"});
  const std::string text = read_text(path);
  ASSERT_EQ(text.size(), 6 + (3u << 20) + 1);
  EXPECT_EQ(text.substr(0, 6), "hello ");
  EXPECT_EQ(text.back(), '!');
}

TEST(AtomicFile, NotCommittedLeavesNothing) {
  TempDir dir;
  {
    AtomicFile file(dir.file("out.vtu"));
    file.write("partial");
  }
  EXPECT_TRUE(dir.entries().empty());
}

TEST(AtomicFile, EscapingExceptionLeavesNothingAndKeepsOldFile) {
  TempDir dir;
  const std::string path = dir.write("out.msh", "old content");
  auto failing_writer = [&] {
    AtomicFile file(path);
    file.write("new but incomplete");
    throw std::runtime_error("meshing failed");
  };
  EXPECT_THROW(failing_writer(), std::runtime_error);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.msh"});
  EXPECT_EQ(read_text(path), "old content");
}

TEST(AtomicFile, CommitReplacesExistingFile) {
  TempDir dir;
  const std::string path = dir.write("out.inp", "old");
  AtomicFile file(path);
  file.write("new");
  file.commit();
  EXPECT_EQ(read_text(path), "new");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.inp"});
  EXPECT_THROW(file.write("more"), InputError);
}

TEST(AtomicFile, UnwritableDirectoryIsInputError) {
  TempDir dir;
  const std::string path = dir.file("missing/sub/out.vtu");
  try {
    AtomicFile file(path);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.field(), "");
    EXPECT_NE(e.problem().find("cannot write: "), std::string::npos) << e.problem();
    EXPECT_NE(e.problem().find("No such file"), std::string::npos) << e.problem();
  }
}

// check_writable says what opening the file would say, without creating anything.
TEST(AtomicFile, CheckWritableAgreesWithOpeningAndCreatesNothing) {
  TempDir dir;
  dir.write("file.txt", "x");
  std::filesystem::create_directory(dir.file("folder"));
  std::filesystem::create_symlink(dir.file("y"), dir.file("x"));
  std::filesystem::create_symlink(dir.file("x"), dir.file("y"));
  std::filesystem::create_symlink("folder/new.vtu", dir.file("dangling"));
  const auto before = dir.entries();
  const auto message = [](const auto& attempt) -> std::string {
    try {
      attempt();
    } catch (const InputError& e) {
      return e.file() + ": " + e.problem();
    }
    return "";
  };
  std::size_t refused = 0;
  for (const std::string& path :
       {dir.file("missing/sub/out.vtu"), dir.file("file.txt/out.vtu"), dir.file("folder"), dir.file("x"),
        dir.file("dangling"), dir.file("file.txt"), dir.file("new.vtu"), dir.file("folder/new.vtu"), std::string("-"),
        std::string(""), dir.file("folder/")}) {
    const std::string checked = message([&] { check_writable(path); });
    EXPECT_EQ(dir.entries(), before) << path;
    EXPECT_EQ(checked, message([&] { AtomicFile file(path); })) << path;
    refused += checked.empty() ? 0 : 1;
  }
  EXPECT_EQ(refused, 6u);  // the missing folder, the file as a folder, the folder, the loop, "", "folder/"
}

TEST(AtomicFile, SymlinkIsFollowedTargetReplacedLinkKept) {
  TempDir dir;
  std::filesystem::create_directory(dir.file("scratch"));
  const std::string target = dir.write("scratch/mesh.vtu", "old");
  const std::string link = dir.file("mesh.vtu");
  std::filesystem::create_symlink("scratch/mesh.vtu", link);  // relative, like `ln -s`
  {
    AtomicFile file(link);
    EXPECT_EQ(std::filesystem::path(file.temporary_path()).parent_path(), dir.path() / "scratch")
        << "the temporary must sit beside the target, on its file system";
    file.write("new");
    file.commit();
  }
  EXPECT_TRUE(std::filesystem::is_symlink(link));
  EXPECT_EQ(read_text(target), "new");
  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"mesh.vtu", "scratch"}));
  EXPECT_EQ(std::filesystem::directory_iterator(dir.path() / "scratch")->path().filename(), "mesh.vtu");
}

TEST(AtomicFile, ChainOfSymlinksAndDanglingLink) {
  TempDir dir;
  std::filesystem::create_symlink(dir.file("b"), dir.file("a"));
  std::filesystem::create_symlink("c.txt", dir.file("b"));  // c.txt does not exist yet
  AtomicFile file(dir.file("a"));
  file.write("created through two links");
  file.commit();
  EXPECT_TRUE(std::filesystem::is_symlink(dir.file("a")));
  EXPECT_TRUE(std::filesystem::is_symlink(dir.file("b")));
  EXPECT_EQ(read_text(dir.file("c.txt")), "created through two links");
}

TEST(AtomicFile, SymlinkLoopIsInputError) {
  TempDir dir;
  std::filesystem::create_symlink(dir.file("y"), dir.file("x"));
  std::filesystem::create_symlink(dir.file("x"), dir.file("y"));
  try {
    AtomicFile file(dir.file("x"));
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), dir.file("x"));
    EXPECT_NE(e.problem().find("symbolic links"), std::string::npos) << e.problem();
  }
}

TEST(AtomicFile, ReplacementKeepsPermissions) {
  TempDir dir;
  const std::string path = dir.write("run.sh", "old");
  std::filesystem::permissions(path, std::filesystem::perms(0750));
  AtomicFile file(path);
  file.write("new");
  file.commit();
  EXPECT_EQ(std::filesystem::status(path).permissions(), std::filesystem::perms(0750));
}

// Runs `body` in a child whose standard output is a pipe; returns what it printed.
template <class Body>
std::string captured_stdout(Body body) {
  int fds[2];
  if (::pipe(fds) != 0) return "pipe failed";
  const pid_t child = ::fork();
  if (child == 0) {
    ::dup2(fds[1], STDOUT_FILENO);
    ::close(fds[0]);
    ::close(fds[1]);
    body();
    std::fflush(stdout);
    ::_exit(0);
  }
  ::close(fds[1]);
  std::string text;
  char chunk[4096];
  for (ssize_t n; (n = ::read(fds[0], chunk, sizeof chunk)) > 0;) text.append(chunk, static_cast<std::size_t>(n));
  ::close(fds[0]);
  int status = 0;
  ::waitpid(child, &status, 0);
  return text;
}

TEST(AtomicFile, DashWritesStandardOutputAfterEarlierPrints) {
  TempDir dir;
  ASSERT_EQ(::chdir(dir.path().c_str()), 0);
  const std::string text = captured_stdout([] {
    std::printf("printed first\n");  // stdio-buffered: must not come after the file's bytes
    AtomicFile file("-");
    EXPECT_EQ(file.temporary_path(), "");
    file.write("{\"format\": \"x\"}\n");
    file.commit();
  });
  ASSERT_EQ(::chdir("/"), 0);
  EXPECT_EQ(text, "printed first\n{\"format\": \"x\"}\n");
  EXPECT_TRUE(dir.entries().empty()) << "no file named '-' and no temporary";
}

TEST(AtomicFile, DevStdoutIsTheDescriptorNotAFile) {
  for (const char* path : {"/dev/stdout", "/dev/fd/1", "/proc/self/fd/1"}) {
    const std::string text = captured_stdout([path] {
      AtomicFile file(path);
      EXPECT_EQ(file.temporary_path(), "");
      file.write("through ");
      file.write(path);
      file.commit();
    });
    EXPECT_EQ(text, std::string("through ") + path);
    EXPECT_TRUE(std::filesystem::is_symlink("/dev/stdout"));
  }
  EXPECT_TRUE(is_standard_output("-"));
  EXPECT_TRUE(is_standard_output("/dev/stdout"));
  EXPECT_TRUE(is_standard_output("/proc/self/fd/1"));
  EXPECT_FALSE(is_standard_output("/dev/stderr"));
  EXPECT_FALSE(is_standard_output("report.json"));
}

TEST(AtomicFile, SymlinkToDevStdoutWritesTheDescriptor) {
  TempDir dir;
  std::filesystem::create_symlink("/dev/stdout", dir.file("report.json"));
  const std::string link = dir.file("report.json");
  const std::string text = captured_stdout([&] {
    AtomicFile file(link);
    file.write("via link");
    file.commit();
  });
  EXPECT_EQ(text, "via link");
  EXPECT_TRUE(std::filesystem::is_symlink(link));
}

TEST(AtomicFile, FifoIsWrittenDirectly) {
  TempDir dir;
  const std::string fifo = dir.file("pipe");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const pid_t reader = ::fork();
  if (reader == 0) {  // reads the FIFO into a file, then exits
    const std::string text = read_text(fifo);
    std::ofstream(fifo + ".read", std::ios::binary) << text;
    ::_exit(0);
  }
  {
    AtomicFile file(fifo);
    EXPECT_EQ(file.temporary_path(), "");
    file.write("through the fifo");
    file.commit();
  }
  int status = 0;
  ::waitpid(reader, &status, 0);
  EXPECT_TRUE(std::filesystem::is_fifo(fifo));
  EXPECT_EQ(read_text(fifo + ".read"), "through the fifo");
}

// After the FIFO test: an implementation that renamed over devices fails there first,
// before it could replace the system's /dev/null. Through a link of our own, too.
TEST(AtomicFile, CharacterDeviceIsWrittenDirectly) {
  TempDir dir;
  std::filesystem::create_symlink("/dev/null", dir.file("null.json"));
  AtomicFile file(dir.file("null.json"));
  EXPECT_EQ(file.temporary_path(), "");
  file.write("discarded");
  file.commit();
  EXPECT_TRUE(std::filesystem::is_symlink(dir.file("null.json")));
  EXPECT_TRUE(std::filesystem::is_character_file("/dev/null"));
}

TEST(AtomicFile, DirectoryAndEmptyPathAreRefusedAtOnce) {
  TempDir dir;
  std::filesystem::create_directory(dir.file("taken"));
  std::filesystem::create_symlink(dir.file("taken"), dir.file("link"));
  for (const std::string& path : {dir.file("taken"), dir.file("link")}) {
    try {
      AtomicFile file(path);
      FAIL() << "expected InputError for " << path;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), path);
      EXPECT_NE(e.problem().find("Is a directory"), std::string::npos) << e.problem();
    }
  }
  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"link", "taken"}));
  try {
    AtomicFile file("");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("the output path is empty"), std::string::npos) << e.what();
  }
}

TEST(AtomicFile, ErrorsNameThePathNotTheTemporary) {
  TempDir dir;
  const std::string path = dir.file("out.txt");
  AtomicFile file(path);
  file.write("data");
  std::filesystem::remove_all(dir.path());  // the rename will fail
  try {
    file.commit();
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(std::string(e.what()).find(".tmp."), std::string::npos) << e.what();
  }
  std::filesystem::create_directories(dir.path());
}

TEST(AtomicFile, RegistryHoldsLiveTemporariesOnly) {
  TempDir dir;
  const std::size_t before = live_temporaries().size();
  {
    AtomicFile a(dir.file("a.txt"));
    AtomicFile b(dir.file("b.txt"));
    auto live = live_temporaries();
    ASSERT_EQ(live.size(), before + 2);
    EXPECT_NE(std::find(live.begin(), live.end(), a.temporary_path()), live.end());
    EXPECT_NE(std::find(live.begin(), live.end(), b.temporary_path()), live.end());
    a.commit();
    EXPECT_EQ(live_temporaries().size(), before + 1);
  }
  EXPECT_EQ(live_temporaries().size(), before);
}

TEST(AtomicFileDeathTest, SignalMidWriteRemovesTheTemporary) {
  // "fast": the child is forked at the statement and writes in this test's directory, which
  // is then checked. ("threadsafe" re-runs the test in a fresh process with a directory of
  // its own: the check below saw an untouched directory, and the child's was left in /tmp.)
  GTEST_FLAG_SET(death_test_style, "fast");
  for (const int signal_number : {SIGTERM, SIGINT}) {
    TempDir dir;
    const std::string path = dir.write("old.vtu", "old");
    EXPECT_EXIT(
        {
          install_signal_cleanup();
          AtomicFile file(path);
          AtomicFile second(dir.file("new.vtu"));
          file.write(std::string(3 << 20, 'x'));  // past the buffer: on disk
          second.write("y");
          std::raise(signal_number);
        },
        ::testing::KilledBySignal(signal_number), "");
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"old.vtu"});
    EXPECT_EQ(read_text(path), "old");
  }
}

TEST(OutputSet, CommitsEverythingAtTheEnd) {
  TempDir dir;
  {
    OutputSet outputs;
    AtomicFile a(dir.file("a.json"));
    a.write("a");
    a.commit();
    EXPECT_TRUE(a.committed());
    EXPECT_FALSE(std::filesystem::exists(dir.file("a.json"))) << "held until the set commits";
    AtomicFile b(dir.file("b.svg"));
    b.write("b");
    b.commit();
    EXPECT_EQ(live_temporaries().size(), 2u);
    outputs.commit();
  }
  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"a.json", "b.svg"}));
  EXPECT_EQ(read_text(dir.file("a.json")), "a");
  EXPECT_TRUE(live_temporaries().empty());
}

TEST(OutputSet, FailedSecondOutputLeavesNoFirstOutput) {
  TempDir dir;
  const std::string kept = dir.write("parts.json", "previous run");
  auto run = [&] {
    OutputSet outputs;
    {
      AtomicFile first(kept);
      first.write("this run");
      first.commit();
    }
    AtomicFile second(dir.file("missing/parts.svg"));  // throws
    outputs.commit();
  };
  EXPECT_THROW(run(), InputError);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"parts.json"});
  EXPECT_EQ(read_text(kept), "previous run");
  EXPECT_TRUE(live_temporaries().empty());
}

TEST(OutputSet, InnerSetJoinsTheOuterOne) {
  TempDir dir;
  auto run = [&](bool fail_after_inner) {
    OutputSet outer;
    {
      OutputSet inner;
      AtomicFile file(dir.file("inner.txt"));
      file.write("x");
      file.commit();
      inner.commit();  // leaves the rename to the outer set
    }
    EXPECT_FALSE(std::filesystem::exists(dir.file("inner.txt")));
    if (fail_after_inner) throw std::runtime_error("later failure");
    outer.commit();
  };
  EXPECT_THROW(run(true), std::runtime_error);
  EXPECT_TRUE(dir.entries().empty());
  run(false);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"inner.txt"});
}

TEST(OutputSet, AfterCommitFilesRenameAtOnce) {
  TempDir dir;
  OutputSet outputs;
  outputs.commit();
  AtomicFile file(dir.file("late.txt"));
  file.write("x");
  file.commit();
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"late.txt"});
}

}  // namespace
}  // namespace cisamr::io

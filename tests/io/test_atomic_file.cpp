#include "io/atomic_file.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
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

TEST(AtomicFile, DestinationIsDirectoryFailsAtCommitAndCleansUp) {
  TempDir dir;
  std::filesystem::create_directory(dir.file("taken"));
  AtomicFile file(dir.file("taken"));
  file.write("data");
  EXPECT_THROW(file.commit(), InputError);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"taken"});
  EXPECT_THROW(file.write("more"), InputError);
}

}  // namespace
}  // namespace cisamr::io

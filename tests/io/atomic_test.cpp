#include "objmap/io/atomic.h"

#include <gtest/gtest.h>

#include "objmap/core/error.h"
#include "support/test_support.h"

namespace objmap::io {
namespace {

namespace fs = std::filesystem;
using test::read_text;
using test::TempDir;
using test::write_text;

std::size_t entries(const fs::path& dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++n;
  return n;
}

TEST(WriteFileAtomic, WritesReplacesAndLeavesNoTemporary) {
  TempDir dir;
  write_file_atomic(dir / "sub" / "a.txt", "first");
  EXPECT_EQ(read_text(dir / "sub" / "a.txt"), "first");
  write_file_atomic(dir / "sub" / "a.txt", "second\n");
  EXPECT_EQ(read_text(dir / "sub" / "a.txt"), "second\n");
  EXPECT_EQ(entries(dir / "sub"), 1u);
}

TEST(WriteFileAtomic, FailureThrowsAndLeavesNothing) {
  TempDir dir;
  write_text(dir / "file", "x");
  // The parent "file" is a regular file: the folder cannot be made.
  EXPECT_THROW(write_file_atomic(dir / "file" / "a.txt", "y"), InputError);
  fs::create_directory(dir / "target");  // a folder where the file should go: rename fails
  EXPECT_THROW(write_file_atomic(dir / "target", "y"), InputError);
  EXPECT_EQ(entries(dir.path()), 2u);
}

TEST(AtomicFile, PiecesThenCommitOrNothing) {
  TempDir dir;
  {
    AtomicFile f(dir / "a.bin");
    f.write("ab", 2);
    f.write("cde", 3);
    EXPECT_FALSE(fs::exists(dir / "a.bin"));  // only the temporary until commit()
    f.commit();
    EXPECT_THROW(f.write("x", 1), InputError);
    EXPECT_THROW(f.commit(), InputError);
  }
  EXPECT_EQ(read_text(dir / "a.bin"), "abcde");
  {
    AtomicFile f(dir / "b.bin");
    f.write("half", 4);
  }  // not committed (as when an exception unwinds): nothing left
  EXPECT_FALSE(fs::exists(dir / "b.bin"));
  EXPECT_EQ(entries(dir.path()), 1u);
}

TEST(StagingDir, CommitReplacesExistingFolder) {
  TempDir dir;
  const fs::path out = dir / "run";
  fs::create_directory(out);
  write_text(out / "old.txt", "old");
  {
    StagingDir staging(out);
    EXPECT_NE(staging.path(), out);
    EXPECT_TRUE(fs::is_directory(staging.path()));
    write_file_atomic(staging.path() / "new.txt", "new");
    EXPECT_TRUE(fs::exists(out / "old.txt"));  // untouched until commit
    staging.commit();
    EXPECT_TRUE(staging.committed());
  }
  EXPECT_EQ(read_text(out / "new.txt"), "new");
  EXPECT_FALSE(fs::exists(out / "old.txt"));
  EXPECT_EQ(entries(dir.path()), 1u);  // no .tmp-/.old- left
}

TEST(StagingDir, NotCommittedLeavesNoTraceAndKeepsOldOutput) {
  TempDir dir;
  const fs::path out = dir / "run";
  fs::create_directory(out);
  write_text(out / "old.txt", "old");
  try {
    StagingDir staging(out);
    write_file_atomic(staging.path() / "half.txt", "half");
    throw std::runtime_error("stage failed");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(read_text(out / "old.txt"), "old");
  EXPECT_EQ(entries(dir.path()), 1u);
  EXPECT_EQ(entries(out), 1u);
}

TEST(StagingDir, RefusesAFileAsOutput) {
  TempDir dir;
  write_text(dir / "run", "x");
  EXPECT_THROW(StagingDir(dir / "run"), InputError);
}

}  // namespace
}  // namespace objmap::io

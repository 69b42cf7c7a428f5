#include "objmap/io/atomic.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "objmap/core/error.h"
#include "support/test_support.h"

namespace objmap::io {
namespace {

namespace fs = std::filesystem;
using test::error_of;
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
  write_text(out / "run.json", "old");
  write_text(out / "old.txt", "old");
  {
    StagingDir staging(out, kRunFolder);
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
  write_text(out / "run.json", "old");
  try {
    StagingDir staging(out, kRunFolder);
    write_file_atomic(staging.path() / "half.txt", "half");
    throw std::runtime_error("stage failed");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(read_text(out / "old.txt"), "old");
  EXPECT_EQ(entries(dir.path()), 1u);
  EXPECT_EQ(entries(out), 2u);
}

// The interrupt's removal, in a child process (death-test fork): it closes the registry for good.
TEST(RemoveUnfinishedOutputs, RemovesTheStagingFolderThenRefusesNewFoldersAndSaysSo) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  TempDir dir;
  const fs::path out = dir / "run";
  EXPECT_EXIT(
      {
        StagingDir staging(out, kRunFolder);
        write_file_atomic(staging.path() / "half.txt", "half");
        const bool before = interrupt_started();
        const std::vector<fs::path> removed = remove_unfinished_outputs();
        bool refused = false;
        try {
          create_output_folders(staging.path() / "again");
        } catch (const InputError& e) {
          refused = std::string(e.what()).find("the process is interrupted") != std::string::npos;
        }
        const bool ok = !before && interrupt_started() && removed.size() == 1 &&
                        removed[0] == staging.path() && !fs::exists(staging.path()) && refused;
        std::_Exit(ok ? 0 : 1);
      },
      ::testing::ExitedWithCode(0), "");
  EXPECT_FALSE(interrupt_started());  // this process's registry is untouched
  EXPECT_EQ(entries(dir.path()), 0u);
}

TEST(StagingDir, RefusesAFileAsOutput) {
  TempDir dir;
  write_text(dir / "run", "x");
  EXPECT_THROW(StagingDir(dir / "run", kRunFolder), InputError);
}

// A dataset given as --out by mistake: refused before any work and at commit, left as it was.
TEST(StagingDir, NeverReplacesAFolderThatIsNotAnEarlierOutput) {
  TempDir dir;
  const fs::path data = dir / "fr1_desk";
  fs::create_directories(data / "rgb");
  fs::create_directories(data / "depth");
  write_text(data / "rgb.txt", "# rgb");
  write_text(data / "depth.txt", "# depth");
  write_text(data / "groundtruth.txt", "# poses");
  const std::string message = error_of([&] { require_replaceable(data, kRunFolder); });
  EXPECT_NE(message.find(data.string() + ": exists and is not an earlier objmap fuse run (it "
                                         "holds depth, depth.txt, groundtruth.txt and 2 more; "
                                         "no run.json), so it is not replaced"),
            std::string::npos)
      << message;
  EXPECT_THROW(StagingDir(data, kRunFolder), InputError);
  EXPECT_THROW(StagingDir(data / "", kRunFolder), InputError);  // "fr1_desk/"
  EXPECT_EQ(entries(data), 5u);
  EXPECT_EQ(entries(dir.path()), 1u);  // no .tmp- left

  // The folder appears (or changes) while the run works: commit() checks again.
  const fs::path out = dir / "run";
  {
    StagingDir staging(out, kRunFolder);
    write_text(staging.path() / "run.json", "new");
    fs::create_directories(out);
    write_text(out / "notes.txt", "mine");
    EXPECT_THROW(staging.commit(), InputError);
  }
  EXPECT_EQ(read_text(out / "notes.txt"), "mine");
  EXPECT_EQ(entries(out), 1u);
  EXPECT_EQ(entries(dir.path()), 2u);  // fr1_desk, run
}

TEST(StagingDir, ReplacesAnEmptyFolderAndEarlierOutputsOfItsKind) {
  TempDir dir;
  fs::create_directories(dir / "empty");
  EXPECT_NO_THROW(require_replaceable(dir / "empty", kReportFolder));
  EXPECT_NO_THROW(require_replaceable(dir / "absent", kReportFolder));
  write_text(dir / "synth" / "synth.json", "{}");
  write_text(dir / "synth" / "rgb.txt", "# rgb");
  EXPECT_NO_THROW(require_replaceable(dir / "synth", kSyntheticSequence));
  EXPECT_THROW(require_replaceable(dir / "synth", kRunFolder), InputError);
  // A marker that is a folder does not count.
  fs::create_directories(dir / "odd" / "run.json");
  EXPECT_THROW(require_replaceable(dir / "odd", kRunFolder), InputError);
  // A segmentation: only <timestamp>.json frame files (detect), or with tracks.json (track).
  write_text(dir / "seg" / "1305031453.359684.json", "{}");
  write_text(dir / "seg" / "1305031453.391690.json", "{}");
  EXPECT_NO_THROW(require_replaceable(dir / "seg", kSegmentationFolder));
  write_text(dir / "seg" / "tracks.json", "{}");
  EXPECT_NO_THROW(require_replaceable(dir / "seg", kSegmentationFolder));
  write_text(dir / "seg_with_notes" / "1305031453.359684.json", "{}");
  write_text(dir / "seg_with_notes" / "notes.json", "{}");
  EXPECT_NE(error_of([&] {
              require_replaceable(dir / "seg_with_notes", kSegmentationFolder);
            }).find("no tracks.json or only frame files"),
            std::string::npos);
  EXPECT_THROW(require_replaceable(dir / "seg", kRunFolder), InputError);
}

// "." names the folder it stands for: the current folder, a dataset here, is refused by name.
TEST(StagingDir, DotIsTheFolderItNames) {
  TempDir dir;
  write_text(dir / "rgb.txt", "# rgb");
  const fs::path cwd = fs::current_path();
  fs::current_path(dir.path());
  const std::string message = error_of([] { StagingDir(".", kRunFolder); });
  fs::current_path(cwd);
  EXPECT_NE(message.find(fs::weakly_canonical(dir.path()).string() + ": exists and is not"),
            std::string::npos)
      << message;
}

}  // namespace
}  // namespace objmap::io

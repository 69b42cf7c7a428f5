#pragma once
#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

// Atomic outputs: a file or a run folder is written under a temporary name in the same folder and
// renamed into place, so a failed or interrupted run never leaves a half-written output behind.
namespace objmap::io {

// An unfinished output (a temporary file or folder) that must go if the process is interrupted:
// registered for the object's lifetime, or until release() (it became the finished output, or is
// gone). The command-line tool takes SIGINT, SIGTERM and SIGHUP on a thread of its own, which calls
// remove_unfinished_outputs() before it ends the process, so that Ctrl-C leaves nothing
// half-written. StagingDir, AtomicFile and the correct stage's scratch folder use it.
class UnfinishedOutput {
 public:
  explicit UnfinishedOutput(std::filesystem::path path);
  ~UnfinishedOutput() { release(); }
  UnfinishedOutput(const UnfinishedOutput&) = delete;
  UnfinishedOutput& operator=(const UnfinishedOutput&) = delete;
  void release();

 private:
  friend class StagingDir;
  void release_locked();  // with the registry's mutex held
  std::filesystem::path path_;
  bool registered_ = false;
};

// Removes every registered unfinished output (files, and folders with their contents) and returns
// those that existed. For the signal thread; safe against a StagingDir::commit() in progress (it
// waits for the commit to end). Afterwards nothing more is registered.
std::vector<std::filesystem::path> remove_unfinished_outputs();

// True once remove_unfinished_outputs() has started: the process is being interrupted and ends by
// its signal. An error another thread meets from then on (a folder removed under it, a folder
// refused) is the interrupt's doing: the objmap command does not report it or exit by it.
bool interrupt_started();

// Creates `folder` and its parents, as std::filesystem::create_directories, unless the process is
// being interrupted: after remove_unfinished_outputs() it throws InputError instead, so that no
// thread makes again a folder inside an unfinished output that the interrupt has just removed.
void create_output_folders(const std::filesystem::path& folder);

// Writes `bytes` to "<file>.tmp-<pid>" and renames it to `file` (replacing an existing
// file). Creates the parent folders if needed. Throws InputError(file, reason) when the file cannot
// be written; the temporary file is removed then.
void write_file_atomic(const std::filesystem::path& file, const std::string& bytes);

// A file written atomically piece by piece (large outputs without a buffer of their size): the
// pieces go to "<file>.tmp-<pid>"; commit() renames it to `file`. Without commit() (an exception),
// the destructor removes the temporary file. Errors are InputError(file, reason), as above.
class AtomicFile {
 public:
  explicit AtomicFile(const std::filesystem::path& file);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  void write(const char* data, std::size_t size);
  void commit();

 private:
  std::filesystem::path file_, tmp_;
  UnfinishedOutput unfinished_;
  int fd_ = -1;
};

// What an existing output folder must hold for objmap to replace it: nothing, or an earlier output
// of the same kind. A folder that holds anything else (a dataset given as --out by mistake, a home
// folder, the parent of the inputs) is never replaced.
struct OutputKind {
  std::string name;                  // for messages: "fuse run", "synthetic sequence", ...
  std::vector<std::string> markers;  // an earlier output holds one of these files
  bool frame_files = false;          // ... or only <timestamp>.json files (a segmentation)
};

extern const OutputKind kRunFolder;           // fuse, correct: run.json
extern const OutputKind kSyntheticSequence;   // synth: synth.json
extern const OutputKind kSegmentationFolder;  // detect, track: <timestamp>.json, tracks.json
extern const OutputKind kReportFolder;        // report: report.html
extern const OutputKind kPipelineFolder;      // run: stages.json
extern const OutputKind kSummaryFolder;       // summary: summary.json

// Throws InputError(out, ...) when `out` exists and is not a folder, or is a folder that is neither
// empty nor an earlier output of `kind` (the message names what it holds). Commands call it before
// their work, so that a refused --out costs nothing.
void require_replaceable(const std::filesystem::path& out, const OutputKind& kind);

// An input of a command: the flag that names it and the path given.
struct NamedPath {
  std::string flag;  // e.g. "--segmentation"
  std::filesystem::path path;
};

// No command writes over what it reads: throws InputError naming both flags when the output `out`
// is one of `inputs` or a folder that holds one (replacing it would delete the input); paths are
// compared after resolving symbolic links, ".." and ".", for outputs that do not exist yet too. An
// output inside an input folder is fine. Empty paths are left out.
void require_not_an_input(const NamedPath& out, const std::vector<NamedPath>& inputs);

// A run folder written atomically: files go to "<out>.tmp-<pid>" (created, empty, by the
// constructor); commit() renames it to `out`, replacing an existing `out` folder if it is an
// earlier output of `kind` (require_replaceable, checked by the constructor and again by commit).
// The destructor removes the temporary folder if commit() was not called (e.g. an exception
// unwound the run).
//
//   io::StagingDir staging(out, io::kRunFolder);
//   write_file_atomic(staging.path() / "objects.json", json);
//   staging.commit();
class StagingDir {
 public:
  // Throws InputError when `out` cannot be replaced (above), or the temporary folder cannot be
  // made.
  StagingDir(const std::filesystem::path& out, const OutputKind& kind);
  ~StagingDir();
  StagingDir(const StagingDir&) = delete;
  StagingDir& operator=(const StagingDir&) = delete;

  const std::filesystem::path& path() const { return staging_; }  // where to write now
  const std::filesystem::path& out() const { return out_; }       // where it ends up
  bool committed() const { return committed_; }
  // Renames the temporary folder to `out`. An existing `out` is moved aside first and deleted only
  // after the rename succeeded (restored if it failed). Throws InputError on failure.
  void commit();
  // The moment commit() put the new folder in place (before it deleted the old one).
  std::chrono::steady_clock::time_point committed_at() const { return committed_at_; }

 private:
  std::filesystem::path out_;
  std::filesystem::path staging_;
  UnfinishedOutput unfinished_;
  OutputKind kind_;
  bool committed_ = false;
  std::chrono::steady_clock::time_point committed_at_;
};

}  // namespace objmap::io

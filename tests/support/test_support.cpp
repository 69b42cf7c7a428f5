#include "support/test_support.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>

#include "objmap/core/error.h"

extern char** environ;

namespace objmap::test {

fs::path data_dir() {
  if (const char* env = std::getenv("OBJMAP_DATA"); env && *env) return fs::path(env);
  return fs::path(OBJMAP_SOURCE_DIR) / ".." / "shared" / "data";
}

bool has_data(const std::string& relative) { return fs::exists(data_dir() / relative); }

bool data_required() {
  const char* env = std::getenv("OBJMAP_REQUIRE_DATA");
  return env && std::string(env) == "1";
}

std::string error_of(const std::function<void()>& call) {
  try {
    call();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

std::string error_reason(const std::function<void()>& call, const std::string& what,
                         std::string* where) {
  try {
    call();
  } catch (const InputError& e) {
    if (where) *where = e.where();
    return e.reason();
  }
  ADD_FAILURE() << "no error for " << what;
  return "";
}

TempDir::TempDir() {
  static std::atomic<int> counter{0};
  std::random_device rd;
  path_ =
      fs::temp_directory_path() / ("objmap-test-" + std::to_string(::getpid()) + "-" +
                                   std::to_string(counter++) + "-" + std::to_string(rd() % 100000));
  fs::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

fs::path cached_output(const std::string& key, const std::vector<std::string>& args,
                       RunResult* result) {
  const fs::path root = fs::path(OBJMAP_TEST_CACHE_DIR);
  const auto stamp = std::to_string(fs::last_write_time(OBJMAP_BINARY).time_since_epoch().count());
  const fs::path dir = root / stamp / key;
  if (fs::exists(dir)) return dir;
  std::error_code ec;
  if (fs::exists(root))
    for (const auto& e : fs::directory_iterator(root))
      if (e.path().filename() != stamp) fs::remove_all(e.path(), ec);
  fs::create_directories(dir.parent_path());
  std::vector<std::string> filled = args;
  for (auto& a : filled)
    if (a == "{OUT}") a = dir.string();
  RunResult r = run_objmap(filled);
  if (result) *result = r;
  if (r.exit_code != 0) fs::remove_all(dir, ec);
  return dir;
}

std::string read_text(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void write_text(const fs::path& file, const std::string& text) {
  if (file.has_parent_path()) fs::create_directories(file.parent_path());
  std::ofstream out(file, std::ios::binary);
  out << text;
}

void copy_tree(const fs::path& from, const fs::path& to) {
  fs::create_directories(to);
  fs::copy(from, to, fs::copy_options::recursive | fs::copy_options::overwrite_existing);
}

fs::path objmap_binary() { return OBJMAP_BINARY; }

RunResult run_objmap(const std::vector<std::string>& args) {
  return run_objmap_interrupted(args, nullptr, 0);
}

RunResult run_objmap_interrupted(const std::vector<std::string>& args,
                                 const std::function<bool()>& ready, int signal) {
  TempDir dir;
  const std::string out_path = (dir.path() / "stdout").string();
  const std::string err_path = (dir.path() / "stderr").string();
  std::vector<std::string> argv_s{OBJMAP_BINARY};
  argv_s.insert(argv_s.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  posix_spawn_file_actions_addopen(&actions, 2, err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  pid_t pid = 0;
  RunResult result;
  if (posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ) == 0) {
    int status = 0;
    if (ready) {
      // Poll until ready() (or the process ended, or 60 s), then signal.
      bool ended = false;
      for (int i = 0; i < 12000 && !ended; ++i) {
        if (ready()) break;
        ended = waitpid(pid, &status, WNOHANG) == pid;
        if (!ended) usleep(5000);
      }
      if (!ended) {
        kill(pid, signal);
        waitpid(pid, &status, 0);
      }
    } else {
      waitpid(pid, &status, 0);
    }
    result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }
  posix_spawn_file_actions_destroy(&actions);
  result.out = read_text(out_path);
  result.err = read_text(err_path);
  return result;
}

}  // namespace objmap::test

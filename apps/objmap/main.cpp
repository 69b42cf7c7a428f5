// objmap: turns a finished RGB-D SLAM run into an object map. One binary, subcommands in the order
// of the pipeline. Exit codes: 0 success, 2 bad input or usage (one line on stderr), 1 internal
// error.
#include <pthread.h>
#include <unistd.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <iostream>
#include <map>
#include <thread>
#include <vector>

#include "command.h"
#include "objmap/core/error.h"
#include "objmap/core/memory.h"
#include "objmap/core/version.h"
#include "objmap/io/atomic.h"

namespace objmap::app {

namespace {
struct Entry {
  int order;
  std::string name;
  SetupFn setup;
};
std::vector<Entry>& registry() {
  static std::vector<Entry> entries;
  return entries;
}
}  // namespace

bool register_command(int order, const std::string& name, SetupFn setup) {
  registry().push_back({order, name, std::move(setup)});
  return true;
}

namespace {

// SIGINT (Ctrl-C), SIGTERM and SIGHUP are blocked in every thread (the workers inherit the mask
// from main) and taken by one thread of their own. It removes the unfinished outputs (temporary
// files and folders), says so in one line, and ends the process by the same signal, so that the
// shell sees an interrupted command (exit status 128 + the signal) and nothing half-written is
// left.
void take_interrupts() {
  sigset_t set;
  sigemptyset(&set);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&set, sig);
  if (pthread_sigmask(SIG_BLOCK, &set, nullptr) != 0) return;
  std::thread([set] {
    int sig = 0;
    if (sigwait(&set, &sig) != 0) return;
    const std::vector<std::filesystem::path> removed = io::remove_unfinished_outputs();
    std::string line = std::string(isatty(STDERR_FILENO) ? "\n" : "") + "objmap: interrupted (" +
                       strsignal(sig) + ")";
    for (std::size_t i = 0; i < removed.size(); ++i)
      line += (i ? ", " : "; removed the unfinished ") + removed[i].string();
    line += "\n";
    [[maybe_unused]] const ssize_t written = ::write(STDERR_FILENO, line.data(), line.size());
    std::signal(sig, SIG_DFL);
    sigset_t one;
    sigemptyset(&one);
    sigaddset(&one, sig);
    pthread_sigmask(SIG_UNBLOCK, &one, nullptr);
    std::raise(sig);
    std::_Exit(128 + sig);  // not reached
  }).detach();
}

// Once the interrupt's thread has started removing the unfinished outputs it ends the process by
// the signal (exit status 128 + the signal). The error that removal may cause on this thread (its
// output folder gone) is not reported, and this thread does not exit first with a code of its
// own: it waits for the signal (blocked here, so pause() never returns).
void wait_if_interrupted() {
  if (!io::interrupt_started()) return;
  for (;;) pause();
}

}  // namespace

void check_naming_flags(const std::function<void()>& check,
                        const std::vector<std::pair<std::string, std::string>>& option_to_flag) {
  try {
    check();
  } catch (const InputError& e) {
    for (const auto& [option, flag] : option_to_flag)
      if (e.where() == option) throw InputError(flag, e.reason());
    throw;
  }
}

void setup_all(CLI::App& app) {
  auto entries = registry();
  std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
    return a.order != b.order ? a.order < b.order : a.name < b.name;
  });
  for (auto& e : entries) e.setup(app);
}

// The first word of argv that names no command of `app` (or of the command it names, for a
// group such as eval), with the commands it could have been; empty when every word is known.
std::string unknown_command(CLI::App& app, int argc, char** argv) {
  CLI::App* group = &app;
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    if (word.empty() || word[0] == '-') return "";
    const auto subcommands = group->get_subcommands({});
    if (subcommands.empty()) return "";
    CLI::App* found = nullptr;
    std::string names;
    for (CLI::App* sub : subcommands) {
      names += (names.empty() ? "" : ", ") + sub->get_name();
      if (sub->get_name() == word) found = sub;
    }
    if (!found) return "unknown command '" + word + "'; expected one of " + names;
    group = found;
  }
  return "";
}

namespace {

// The exception `app.parse` threw, said on stderr (help and version on stdout), as an exit code:
// 2 for bad input or usage, 1 for an internal error.
int exit_code_of_current_exception(CLI::App& app, int argc, char** argv) {
  // A word that names no command is a usage error even beside --help, which CLI11 honours first
  // (`objmap NOSUCHCOMMAND --help` printed the main help and exited 0).
  const auto help_or_unknown = [&](const CLI::ParseError& e) {
    const std::string unknown = unknown_command(app, argc, argv);
    if (unknown.empty()) return app.exit(e);
    std::cerr << "objmap: usage error: " << unknown << " (see 'objmap --help')\n";
    return 2;
  };
  try {
    throw;
  } catch (const CLI::CallForHelp& e) {
    return help_or_unknown(e);
  } catch (const CLI::CallForAllHelp& e) {
    return help_or_unknown(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    const std::string unknown = unknown_command(app, argc, argv);
    std::cerr << "objmap: usage error: " << (unknown.empty() ? std::string(e.what()) : unknown)
              << " (see 'objmap --help')\n";
    return 2;
  } catch (const InputError& e) {
    std::cerr << "objmap: error: " << e.what() << "\n";
    return 2;
  } catch (const std::filesystem::filesystem_error& e) {
    // A path the system cannot resolve or read (a symbolic link loop, no permission): bad input.
    std::cerr << "objmap: error: " << e.path1().string() << ": " << e.code().message()
              << "; expected a path objmap can read or write\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "objmap: internal error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace

}  // namespace objmap::app

int main(int argc, char** argv) {
  objmap::app::take_interrupts();  // first: before any thread starts
  objmap::keep_freed_memory();
  CLI::App app{
      "objmap: object-oriented semantic maps from a finished RGB-D SLAM run.\n"
      "One command: objmap run (detect -> track -> fuse -> report on a recording).\n"
      "Pipeline: synth | validate -> detect -> track -> fuse -> correct -> eval -> report.\n"
      "Run 'objmap <command> --help' for the options of one command."};
  app.set_version_flag("--version", std::string("objmap ") + objmap::version());
  app.require_subcommand(1);
  objmap::app::setup_all(app);
  try {
    app.parse(argc, argv);
  } catch (...) {
    objmap::app::wait_if_interrupted();
    return objmap::app::exit_code_of_current_exception(app, argc, argv);
  }
  objmap::app::wait_if_interrupted();
  return 0;
}

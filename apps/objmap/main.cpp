// objmap: turns a finished RGB-D SLAM run into an object map. One binary, subcommands in the order
// of the pipeline. Exit codes: 0 success, 2 bad input or usage (one line on stderr), 1 internal
// error.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <exception>
#include <iostream>
#include <map>
#include <vector>

#include "command.h"
#include "objmap/core/error.h"
#include "objmap/version.h"

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

void setup_all(CLI::App& app) {
  auto entries = registry();
  std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
    return a.order != b.order ? a.order < b.order : a.name < b.name;
  });
  for (auto& e : entries) e.setup(app);
}

}  // namespace objmap::app

int main(int argc, char** argv) {
  CLI::App app{
      "objmap: object-oriented semantic maps from a finished RGB-D SLAM run.\n"
      "Pipeline: synth | validate -> detect -> track -> fuse -> correct -> eval -> report.\n"
      "Run 'objmap <command> --help' for the options of one command."};
  app.set_version_flag("--version", std::string("objmap ") + objmap::version());
  app.require_subcommand(1);
  objmap::app::setup_all(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "objmap: usage error: " << e.what() << " (see 'objmap --help')\n";
    return 2;
  } catch (const objmap::InputError& e) {
    std::cerr << "objmap: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "objmap: internal error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

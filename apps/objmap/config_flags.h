#pragma once
#include <CLI/CLI.hpp>
#include <functional>
#include <set>
#include <string>
#include <vector>

#include "command.h"
#include "objmap/pipeline/config.h"

namespace objmap::app {

// Declares one flag per field of a command's config table, bound to the options struct, and applies
// a --config file afterwards to the fields whose flag was not given (flags win over the file).
class ConfigFlags {
 public:
  // table_of(Options&) -> std::vector<pipeline::ConfigField>
  template <typename Options, typename TableFn>
  ConfigFlags(CLI::App* cmd, TableFn table_of, Options& options) {
    fields_ = table_of(options);
    for (auto& f : fields_) {
      CLI::Option* opt = nullptr;
      std::visit(
          [&](auto* target) {
            using T = std::remove_pointer_t<decltype(target)>;
            if constexpr (std::is_same_v<T, bool>)
              opt = cmd->add_option(f.flag, *target, f.help + " (true/false)");
            else
              opt = cmd->add_option(f.flag, *target, f.help);
          },
          f.target);
      opt->capture_default_str()->group("Tuning (also in --config)");
      options_.push_back(opt);
    }
    // Copies the fields of `from` into `to`, but not those given as a flag or in the file.
    copy_unset_ = [this, table_of](void* from, void* to) {
      auto from_fields = table_of(*static_cast<Options*>(from));
      auto to_fields = table_of(*static_cast<Options*>(to));
      for (std::size_t i = 0; i < to_fields.size(); ++i) {
        if (options_[i]->count() > 0 || from_file_.count(to_fields[i].key) > 0) continue;
        std::visit(
            [&](auto* dst) {
              using P = decltype(dst);
              *dst = *std::get<P>(from_fields[i].target);
            },
            to_fields[i].target);
      }
    };
    apply_ = [this, table_of](const std::string& file, void* opts) {
      Options& target = *static_cast<Options*>(opts);
      Options from_file = target;  // flags already applied; the file fills the rest
      auto file_fields = table_of(from_file);
      const std::vector<std::string> set = pipeline::apply_config_file(file, file_fields);
      auto target_fields = table_of(target);
      for (std::size_t i = 0; i < target_fields.size(); ++i) {
        if (options_[i]->count() > 0) continue;
        std::visit(
            [&](auto* dst) {
              using P = decltype(dst);
              *dst = *std::get<P>(file_fields[i].target);
            },
            target_fields[i].target);
      }
      from_file_.insert(set.begin(), set.end());
    };
  }

  template <typename Options>
  void apply_config(const std::string& file, Options& options) {
    if (!file.empty()) apply_(file, &options);
  }

  // After apply_config(): `preset(copy)` sets the options of a method on a copy of `options`;
  // every field that was neither given as a flag nor set by the config file takes the preset's
  // value (an option given explicitly overrides the preset).
  template <typename Options, typename Preset>
  void apply_preset(Options& options, Preset&& preset) {
    Options with_preset = options;
    preset(with_preset);
    copy_unset_(&with_preset, &options);
  }

  // options.check(); an error naming a field by its config key names its flag too:
  // "objects.weight_id (--weight-id): must be >= 0, got -1".
  template <typename Options>
  void check(const Options& options) const {
    std::vector<std::pair<std::string, std::string>> key_to_name;
    for (const auto& f : fields_) key_to_name.emplace_back(f.key, f.key + " (" + f.flag + ")");
    check_naming_flags([&] { options.check(); }, key_to_name);
  }

 private:
  std::vector<pipeline::ConfigField> fields_;
  std::vector<CLI::Option*> options_;
  std::function<void(const std::string&, void*)> apply_;
  std::function<void(void*, void*)> copy_unset_;
  std::set<std::string> from_file_;  // keys the config file set
};

}  // namespace objmap::app

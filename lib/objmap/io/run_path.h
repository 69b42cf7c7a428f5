#pragma once
#include <filesystem>
#include <string>

// The files a run folder names itself (objects.json "ply": objects/<id>_<class>.ply): a run folder
// may come from someone else, so a path read from it is only followed when it stays inside it.
// The recording a run was made from (run.json inputs.dataset, .trajectory, .segmentation) lies
// outside the run by design and is not a path of this kind.
namespace objmap::io {

// `run` / `relative`, when it resolves inside the run folder: symlinks followed as far as they
// exist (std::filesystem::weakly_canonical), so that neither "..", an absolute path nor a symlink
// leads out. Otherwise throws InputError("<file>: <field>", "'<relative>' resolves outside the run
// folder <run>; expected a path inside it"); `file` is the file the path was read from and `field`
// its place in it, e.g. "objects[3].ply".
std::filesystem::path path_in_run(const std::filesystem::path& run, const std::string& relative,
                                  const std::filesystem::path& file, const std::string& field);

}  // namespace objmap::io

#include "objmap/change/diff_query.h"

#include <algorithm>
#include <cctype>
#include <set>
#include <sstream>

#include "objmap/core/error.h"
#include "objmap/scene/query.h"
#include "objmap/segmentation/coco_classes.h"

namespace objmap::change {
namespace {

const char* kGrammar =
    "expected STATUS (moved|added|removed|changed class|not seen again|not seen before|unchanged|"
    "changed) and/or a CLASS, e.g. \"what moved\", \"moved cup\", \"removed chair\"";

const std::set<std::string> kFiller = {
    "what", "which", "who",  "is",   "are",   "was",   "were",   "has",     "have",  "been",
    "got",  "did",   "do",   "does", "the",   "a",     "an",     "any",     "all",   "and",
    "or",   "since", "last", "time", "visit", "there", "object", "objects", "thing", "things"};

// The words of the text: lower case, split at anything but letters, digits, '-' and '_'.
std::vector<std::string> words_of(const std::string& text) {
  std::string clean;
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    clean += std::isalnum(c) || ch == '-' || ch == '_' ? static_cast<char>(std::tolower(c)) : ' ';
  }
  std::istringstream in(clean);
  std::vector<std::string> words;
  for (std::string w; in >> w;) words.push_back(w);
  return words;
}

bool at(const std::vector<std::string>& w, std::size_t i, const char* word) {
  return i < w.size() && w[i] == word;
}

// The statuses the words from `i` name (how many words they take), or none (0).
std::size_t status_words(const std::vector<std::string>& w, std::size_t i,
                         std::set<std::string>& statuses) {
  const std::string& x = w[i];
  if (x == "moved" || x == "added" || x == "removed" || x == "unchanged" || x == "changed_class" ||
      x == "not_seen_again" || x == "not_seen_before") {
    statuses.insert(x);
    return 1;
  }
  if (x == "changed" && at(w, i + 1, "class")) {
    statuses.insert("changed_class");
    return 2;
  }
  if (x == "changed") {
    statuses.insert({"moved", "added", "removed", "changed_class"});
    return 1;
  }
  if (x == "not" && at(w, i + 1, "seen")) {
    const bool again = at(w, i + 2, "again"), before = at(w, i + 2, "before");
    if (!before) statuses.insert("not_seen_again");
    if (!again) statuses.insert("not_seen_before");
    return again || before ? 3 : 2;
  }
  return 0;
}

std::string joined(const std::vector<std::string>& words) {
  std::string out;
  for (const std::string& w : words) out += (out.empty() ? "" : " ") + w;
  return out;
}

}  // namespace

DiffQuery parse_diff_query(const std::string& text, const io::DiffFile& diff) {
  DiffQuery q;
  q.text = text;
  const std::vector<std::string> w = words_of(text);
  std::set<std::string> statuses;
  std::vector<std::string> rest;  // the words left for the class
  for (std::size_t i = 0; i < w.size();) {
    if (const std::size_t n = status_words(w, i, statuses)) {
      i += n;
      continue;
    }
    if (!kFiller.count(w[i])) rest.push_back(w[i]);
    ++i;
  }
  for (const char* s : io::kDiffStatuses)
    if (statuses.count(s)) q.statuses.push_back(s);
  if (!rest.empty()) {
    std::set<std::string> known(segmentation::coco80_names().begin(),
                                segmentation::coco80_names().end());
    for (const io::DiffObject& o : diff.objects)
      for (const auto* side : {&o.before, &o.after})
        if (*side) known.insert(segmentation::canonical_class((*side)->class_name));
    const auto name = scene::class_named(joined(rest), known);
    require(name.has_value(), "query",
            "'" + joined(rest) + "' is neither a status nor a class of COCO-80 or of this diff; " +
                kGrammar);
    q.class_name = *name;
  }
  require(!q.statuses.empty() || !q.class_name.empty(), "query",
          "'" + text + "' asks for nothing; " + kGrammar);
  return q;
}

std::vector<const io::DiffObject*> run_diff_query(const DiffQuery& q, const io::DiffFile& diff) {
  const auto has_class = [&](const std::optional<io::DiffSide>& side) {
    return side && segmentation::canonical_class(side->class_name) == q.class_name;
  };
  std::vector<const io::DiffObject*> out;
  for (const io::DiffObject& o : diff.objects) {
    const bool status_ok = q.statuses.empty() || std::find(q.statuses.begin(), q.statuses.end(),
                                                           o.status) != q.statuses.end();
    const bool class_ok = q.class_name.empty() || has_class(o.before) || has_class(o.after);
    if (status_ok && class_ok) out.push_back(&o);
  }
  return out;
}

}  // namespace objmap::change

#pragma once
#include <string>
#include <vector>

#include "objmap/io/diff_json.h"

// `objmap query --diff DIFF "what moved"`: questions asked of a diff.json (docs/change.md,
// "Questions"). Grammar, words in any order, case ignored:
//   STATUS... [CLASS]   or   CLASS
//   STATUS = moved | added | removed | changed class | not seen again | not seen before |
//            unchanged | changed (moved, added, removed and changed class together)
//   CLASS  = a class of COCO-80 or of the diff (any spelling canonical_class accepts, plural too)
// Several statuses ask for any of them ("moved or removed"); a class alone asks for every object
// of that class whatever its status. Filler words are ignored: what, which, who, is, are, was,
// were, has, have, been, got, did, do, does, the, a, an, any, all, and, or, since, last, time,
// visit, there, object(s), thing(s), "?".
namespace objmap::change {

struct DiffQuery {
  std::string text;
  std::vector<std::string> statuses;  // diff.json statuses asked for, in kDiffStatuses order;
                                      // empty: any
  std::string class_name;             // canonical; empty: any
};

// Parses `text`; the classes known are COCO-80's and the diff's. Throws InputError("query", ...)
// naming the words it did not understand, or saying the query asks for nothing.
DiffQuery parse_diff_query(const std::string& text, const io::DiffFile& diff);

// The objects of the diff that answer the query, in the file's order. An object matches a class
// when its before or its after class is that class.
std::vector<const io::DiffObject*> run_diff_query(const DiffQuery& query, const io::DiffFile& diff);

}  // namespace objmap::change

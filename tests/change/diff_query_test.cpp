// change::parse_diff_query / run_diff_query: the grammar of `objmap query --diff` (docs/change.md,
// "Questions") on a small diff.
#include <gtest/gtest.h>

#include "objmap/change/diff_query.h"
#include "objmap/core/error.h"

namespace objmap::change {
namespace {

io::DiffObject object(const std::string& status, std::optional<io::DiffSide> before,
                      std::optional<io::DiffSide> after) {
  io::DiffObject o;
  o.status = status;
  o.before = std::move(before);
  o.after = std::move(after);
  return o;
}

io::DiffSide side(int id, const std::string& cls) { return {id, cls, Vec3::Zero(), Vec3::Zero()}; }

io::DiffFile small_diff() {
  io::DiffFile d;
  d.objects = {object("moved", side(1, "cup"), side(11, "cup")),
               object("moved", side(2, "book"), side(12, "book")),
               object("removed", side(3, "chair"), std::nullopt),
               object("added", std::nullopt, side(14, "cup")),
               object("changed_class", side(5, "laptop"), side(15, "tv monitor")),
               object("not_seen_again", side(6, "mouse"), std::nullopt),
               object("not_seen_before", std::nullopt, side(17, "keyboard")),
               object("unchanged", side(8, "cup"), side(18, "cup"))};
  return d;
}

std::vector<std::string> answer(const std::string& text) {
  const io::DiffFile d = small_diff();
  std::vector<std::string> out;
  for (const io::DiffObject* o : run_diff_query(parse_diff_query(text, d), d))
    out.push_back(o->status + " " + std::to_string(o->before ? o->before->id : o->after->id));
  return out;
}

using Answers = std::vector<std::string>;

TEST(DiffQuery, StatusesClassesAndTheirCombinations) {
  EXPECT_EQ(answer("what moved"), (Answers{"moved 1", "moved 2"}));
  EXPECT_EQ(answer("What moved?"), (Answers{"moved 1", "moved 2"}));
  EXPECT_EQ(answer("moved cup"), (Answers{"moved 1"}));
  EXPECT_EQ(answer("which cups moved"), (Answers{"moved 1"}));
  EXPECT_EQ(answer("removed chair"), (Answers{"removed 3"}));
  EXPECT_EQ(answer("what was removed"), (Answers{"removed 3"}));
  EXPECT_EQ(answer("what is added"), (Answers{"added 14"}));
  EXPECT_EQ(answer("changed class"), (Answers{"changed_class 5"}));
  EXPECT_EQ(answer("not seen again"), (Answers{"not_seen_again 6"}));
  EXPECT_EQ(answer("not seen before"), (Answers{"not_seen_before 17"}));
  EXPECT_EQ(answer("not seen"), (Answers{"not_seen_again 6", "not_seen_before 17"}));
  EXPECT_EQ(answer("unchanged"), (Answers{"unchanged 8"}));
  EXPECT_EQ(answer("what changed"),
            (Answers{"moved 1", "moved 2", "removed 3", "added 14", "changed_class 5"}));
  EXPECT_EQ(answer("moved or removed"), (Answers{"moved 1", "moved 2", "removed 3"}));
  // A class alone: every object of it, whatever its status; before or after class.
  EXPECT_EQ(answer("cup"), (Answers{"moved 1", "added 14", "unchanged 8"}));
  EXPECT_EQ(answer("tv monitor"), (Answers{"changed_class 5"}));
  EXPECT_EQ(answer("removed cup"), Answers{});  // understood, nothing matches
}

TEST(DiffQuery, WordsNotUnderstoodAndEmptyQueriesAreNamed) {
  const io::DiffFile d = small_diff();
  try {
    parse_diff_query("what flew", d);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'flew'"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
  }
  EXPECT_THROW(parse_diff_query("what is", d), InputError);
  EXPECT_THROW(parse_diff_query("", d), InputError);
  EXPECT_THROW(parse_diff_query("moved spaceship", d), InputError);
  // COCO's classes are known even when the diff has none of them.
  EXPECT_TRUE(run_diff_query(parse_diff_query("moved bicycle", d), d).empty());
}

}  // namespace
}  // namespace objmap::change

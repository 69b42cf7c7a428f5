// What moves is not the map (fusion/movers.h): a person's or an animal's object is a sighting.
#include <gtest/gtest.h>

#include "objmap/core/error.h"
#include "objmap/fusion/movers.h"

namespace objmap::fusion {
namespace {

ObjectRecord mover_record(int id, const std::string& name) {
  ObjectRecord r;
  r.id = id;
  r.class_name = name;
  return r;
}

TEST(Movers, PersonsAndAnimalsAreTakenOutTheRestKeepTheirOrder) {
  std::vector<ObjectRecord> records = {mover_record(1, "chair"), mover_record(2, "person"),
                                       mover_record(3, "cup"), mover_record(4, "Dog"),
                                       mover_record(5, "teddy bear")};
  const std::vector<ObjectRecord> moving = take_movers(records, parse_movers("default", "m"));
  ASSERT_EQ(moving.size(), 2u);
  EXPECT_EQ(moving[0].id, 2);
  EXPECT_EQ(moving[1].id, 4);
  ASSERT_EQ(records.size(), 3u);
  EXPECT_EQ(records[0].id, 1);
  EXPECT_EQ(records[1].id, 3);
  EXPECT_EQ(records[2].id, 5) << "a teddy bear does not move by itself";
}

TEST(Movers, NoneKeepsEveryObjectAListNamesItsClasses) {
  std::vector<ObjectRecord> records = {mover_record(1, "person"), mover_record(2, "dog")};
  EXPECT_TRUE(take_movers(records, parse_movers("none", "m")).empty());
  EXPECT_EQ(records.size(), 2u);
  const std::vector<std::string> dogs = parse_movers("Dog, dog,teddy_bear", "m");
  EXPECT_EQ(dogs, (std::vector<std::string>{"dog", "teddy bear"}));
  const std::vector<ObjectRecord> moving = take_movers(records, dogs);
  ASSERT_EQ(moving.size(), 1u);
  EXPECT_EQ(moving[0].id, 2);
  EXPECT_EQ(records.size(), 1u);
}

TEST(Movers, AnEmptyNameIsNamed) {
  try {
    parse_movers("person,,dog", "objects.movers");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "objects.movers");
  }
  EXPECT_THROW(parse_movers("", "objects.movers"), InputError);
}

}  // namespace
}  // namespace objmap::fusion

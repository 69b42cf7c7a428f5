#include "objmap/core/copy_on_write.h"

#include <gtest/gtest.h>

#include <vector>

namespace objmap {
namespace {

TEST(CopyOnWrite, CopiesShareTheValueUntilOneWritesIt) {
  CopyOnWrite<std::vector<int>> a(std::vector<int>{1, 2, 3});
  EXPECT_FALSE(a.shared());
  CopyOnWrite<std::vector<int>> b = a;
  EXPECT_TRUE(a.shared());
  EXPECT_EQ(&*a, &*b);  // one value
  b.write().push_back(4);
  EXPECT_FALSE(a.shared());
  EXPECT_NE(&*a, &*b);
  EXPECT_EQ(*a, (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(*b, (std::vector<int>{1, 2, 3, 4}));
  const std::vector<int>* own = &*b;
  b.write().push_back(5);  // its own already: written in place
  EXPECT_EQ(&*b, own);
  a = std::vector<int>{7};  // a new value, b's untouched
  EXPECT_EQ(a->size(), 1u);
  EXPECT_EQ(b->size(), 5u);
}

}  // namespace
}  // namespace objmap

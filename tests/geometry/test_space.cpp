#include "curvlab/geometry/space.hpp"
#include <gtest/gtest.h>
TEST(Space, Placeholder) { EXPECT_EQ(curvlab::geometry::Space{}.k(), 0.0); }

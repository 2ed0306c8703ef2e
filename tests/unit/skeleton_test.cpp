#include <gtest/gtest.h>
#include "chatterlab/params.hpp"
TEST(Skeleton, Builds) { EXPECT_EQ(chatterlab::to_string(chatterlab::ValueKind::real), "real number"); }

// The HDF5 wrapper (src/io/h5file.cpp): attributes, row slabs, scalars, and
// the errors of missing or mistyped items.
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "io_helpers.hpp"
#include "snl/io/h5file.hpp"

using namespace snl;
using snl::test::read_error;
using snl::test::scratch;

TEST(H5FileTest, AttributesAndMissing) {
  const std::string path = scratch("attrs.h5");
  {
    H5File f(path, MPI_COMM_SELF, H5File::Mode::kCreate);
    f.set_attr("s", std::string("héllo"));
    f.set_attr("i", std::int64_t{-42});
    f.set_attr("d", 2.5);
    f.set_attr("grp/sub", std::int64_t{7});
    f.set_attr("s", std::string("replaced"));
    f.commit();
  }
  H5File f(path, MPI_COMM_SELF, H5File::Mode::kRead);
  EXPECT_EQ(f.attr_string("s"), "replaced");
  EXPECT_EQ(f.attr_int("i"), -42);
  EXPECT_EQ(f.attr_double("d"), 2.5);
  EXPECT_EQ(f.attr_double("i"), -42.0);
  EXPECT_EQ(f.attr_int("grp/sub"), 7);
  EXPECT_TRUE(f.has_attr("grp/sub"));
  EXPECT_FALSE(f.has_attr("nope"));
  EXPECT_FALSE(f.has_attr("nogroup/nope"));
  EXPECT_FALSE(f.has_dataset("grp"));
  try {
    f.attr_int("nope");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), path + ": attribute 'nope' not found");
  }
  EXPECT_THROW(f.attr_int("d"), Error);  // 2.5 is not an integer
  EXPECT_THROW(f.attr_string("i"), Error);
  EXPECT_THROW(f.read_rows_double("nope", 0, 0), Error);
  EXPECT_THROW(f.set_attr("x", std::int64_t{1}), Error);  // read-only
}

TEST(H5FileTest, RowsAndScalar) {
  const std::string path = scratch("rows.h5");
  std::vector<double> d(20);
  for (int k = 0; k < 20; ++k) d[k] = k * 0.5;
  std::vector<std::uint8_t> u = {1, 2, 255};
  {
    H5File f(path, MPI_COMM_SELF, H5File::Mode::kCreate);
    f.write_rows("a/b/d", 10, 2, 0, d.data(), 4);  // two slabs of one dataset
    f.write_rows("a/b/d", 10, 2, 4, d.data() + 8, 6);
    f.write_rows("u", 3, 0, 0, u.data(), 3);
    f.write_scalar("s", 3.25);
    f.write_replicated("r", std::vector<std::int64_t>{5, 6});
    f.commit();
  }
  H5File f(path, MPI_COMM_SELF, H5File::Mode::kRead);
  EXPECT_EQ(f.shape("a/b/d"), (std::vector<std::uint64_t>{10, 2}));
  EXPECT_EQ(f.shape("s"), (std::vector<std::uint64_t>{}));
  EXPECT_EQ(f.read_rows_double("a/b/d", 0, 10), d);
  EXPECT_EQ(f.read_rows_double("a/b/d", 3, 2), (std::vector<double>{3, 3.5, 4, 4.5}));
  EXPECT_EQ(f.read_rows_u8("u", 0, 3), u);
  EXPECT_EQ(f.read_rows_int("r", 1, 1), (std::vector<std::int64_t>{6}));
  EXPECT_EQ(f.read_scalar("s"), 3.25);
  EXPECT_TRUE(f.read_rows_double("a/b/d", 10, 0).empty());
  EXPECT_THROW(f.read_rows_double("a/b/d", 8, 3), Error);  // beyond the end
  EXPECT_EQ(f.list("a"), (std::vector<std::string>{"b"}));
}

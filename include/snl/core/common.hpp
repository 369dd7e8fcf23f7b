#pragma once
// Basic types shared by every part of snl.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace snl {

/// Index of a node inside one rank: owned nodes [0, n_owned), ghosts appended.
using LocalId = std::int32_t;
/// Index of a node in the whole network (sensor ids 0..n-1 of the file).
using GlobalId = std::int64_t;

/// Every user-facing failure (bad input, I/O error, invalid option) is an snl::Error.
/// Its message is complete and meant to be printed as is.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A numerical method found no solution (an SDP solver's failure or an
/// infeasible SDP): the command exits with status 4 and writes nothing.
class NumericalFailure : public Error {
 public:
  using Error::Error;
};

/// Frees v's storage now. (`v = {}` does not: it assigns an empty
/// initializer list and keeps the capacity.)
template <class T, class A>
void release(std::vector<T, A>& v) {
  std::vector<T, A>().swap(v);
}

}  // namespace snl

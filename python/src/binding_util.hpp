#pragma once
// Helpers shared by the binding's translation units (module.cpp, consensus.cpp):
// communicators from mpi4py handles, numpy arrays to and from vectors, broadcasts.
#include <mpi.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include "snl/core/mpi_util.hpp"

namespace snl_py {

namespace py = pybind11;

// An mpi4py handle (an int) as the MPI's handle type: a pointer (Open MPI) or an int (MPICH).
template <class C>
C comm_from_handle(std::uintptr_t h) {
  if constexpr (std::is_pointer_v<C>)
    return reinterpret_cast<C>(h);
  else
    return static_cast<C>(h);
}

// A communicator from its mpi4py handle; None: MPI_COMM_WORLD.
inline MPI_Comm to_comm(const py::object& handle) {
  if (handle.is_none()) return MPI_COMM_WORLD;
  return comm_from_handle<MPI_Comm>(handle.cast<std::uintptr_t>());
}

template <class T>
using Arr = py::array_t<T, py::array::c_style | py::array::forcecast>;

template <class T>
std::vector<T> to_vec(const py::object& o) {
  if (o.is_none()) return {};
  const Arr<T> a = Arr<T>::ensure(o);
  if (!a) throw py::value_error("expected a numeric array");
  return std::vector<T>(a.data(), a.data() + a.size());
}

template <class T>
py::array_t<T> to_array(const std::vector<T>& v, std::vector<py::ssize_t> shape) {
  py::array_t<T> a(shape);
  if (!v.empty()) std::memcpy(a.mutable_data(), v.data(), v.size() * sizeof(T));
  return a;
}

// A vector broadcast from rank 0 (the other ranks' copies are replaced).
template <class T>
void bcast_vec(MPI_Comm comm, std::vector<T>& v) {
  std::int64_t n = static_cast<std::int64_t>(v.size());
  snl::bcast_bytes(comm, &n, sizeof n);
  v.resize(static_cast<std::size_t>(n));
  if (n > 0) snl::bcast_bytes(comm, v.data(), v.size() * sizeof(T));
}

/// Python called from inside a collective run (callbacks, Ctrl-C): poll()
/// runs the call with the GIL held and notes what it asked for; agree() makes
/// every rank see the worst request of any rank (so all stop at the same
/// point); raise_if_needed() turns it into the Python exception after the run.
class PyGuard {
 public:
  enum Status : int { kContinue = 0, kStop = 1, kError = 2, kInterrupt = 3 };
  explicit PyGuard(MPI_Comm comm) : comm_(comm) {}
  /// GIL held. A pending Ctrl-C, or `call` raising, is this rank's request;
  /// `call` returns true to stop the run.
  template <class Call>
  int poll(Call&& call) {
    if (PyErr_CheckSignals() != 0) {
      if (PyErr_ExceptionMatches(PyExc_KeyboardInterrupt)) {
        PyErr_Clear();
        return kInterrupt;
      }
      error_ = py::error_already_set();
      return kError;
    }
    try {
      return call() ? kStop : kContinue;
    } catch (py::error_already_set& e) {
      if (e.matches(PyExc_KeyboardInterrupt)) return kInterrupt;
      error_ = std::move(e);
      return kError;
    }
  }
  /// Collective (GIL released): the worst request over the ranks.
  int agree(int mine) {
    int all = mine;
    MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MAX, comm_);
    if (all != kContinue) status_ = all;
    return all;
  }
  /// GIL held, after the run: raises what stopped it, on every rank.
  void raise_if_needed() {
    if (status_ == kInterrupt) {
      PyErr_SetNone(PyExc_KeyboardInterrupt);
      throw py::error_already_set();
    }
    if (status_ == kError) {
      if (error_) {
        error_->restore();
        throw py::error_already_set();
      }
      throw std::runtime_error("a callback raised an exception on another rank");
    }
  }
  MPI_Comm comm() const { return comm_; }

 private:
  MPI_Comm comm_;
  int status_ = kContinue;
  std::optional<py::error_already_set> error_;
};

/// Adds snl.consensus's functions (consensus.cpp).
void add_consensus(py::module_& m);

}  // namespace snl_py

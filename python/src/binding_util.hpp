#pragma once
// Helpers shared by the binding's translation units (module.cpp, consensus.cpp):
// communicators from mpi4py handles, numpy arrays to and from vectors, broadcasts.
#include <mpi.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <cstring>
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

/// Adds snl.consensus's functions (consensus.cpp).
void add_consensus(py::module_& m);

}  // namespace snl_py

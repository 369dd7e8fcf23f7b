#pragma once
// One place that turns the runtime dimension p (1, 2 or 3) into a template
// argument: with_dim(p, [&](auto P) { f<decltype(P)::value>(...); }) calls f<1>,
// f<2> or f<3>.
// Kernels are templated on p so their inner loops have a fixed trip count.
#include <type_traits>

namespace snl::detail {

template <class F>
decltype(auto) with_dim(int p, F&& f) {
  if (p == 1) return f(std::integral_constant<int, 1>{});
  if (p == 2) return f(std::integral_constant<int, 2>{});
  return f(std::integral_constant<int, 3>{});
}

}  // namespace snl::detail

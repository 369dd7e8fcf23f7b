// The local objectives f_p of the four problem families (docs/consensus.md):
// value, gradient and Hessian at a q-vector x.
#include <cmath>
#include <cstring>
#include <vector>

#include "snl/consensus/problem.hpp"

namespace snl::consensus {

namespace {

/// log(1 + e^t) without overflow for large t or loss of precision for very negative t.
inline double softplus(double t) { return t > 0 ? t + std::log1p(std::exp(-t)) : std::log1p(std::exp(t)); }

/// 1 / (1 + e^-t), evaluated so that e^(...) never overflows.
inline double sigmoid(double t) {
  if (t >= 0) return 1.0 / (1.0 + std::exp(-t));
  const double e = std::exp(t);
  return e / (1.0 + e);
}

inline double dot(const double* a, const double* b, int q) {
  double s = 0;
  for (int k = 0; k < q; ++k) s += a[k] * b[k];
  return s;
}

}  // namespace

LocalObjectives::LocalObjectives(const ProblemData& data, const std::vector<GlobalId>& nodes)
    : family_(data.family), dim_(data.dim), n_global_(data.num_nodes), lambda_(data.lambda), nodes_(nodes) {
  const std::size_t m = nodes_.size(), q = static_cast<std::size_t>(dim_);
  for (GlobalId g : nodes_)
    if (g < 0 || g >= n_global_) throw Error("LocalObjectives: node id " + std::to_string(g) + " out of range");
  switch (family_) {
    case Family::kExp:
      for (GlobalId g : nodes_) {
        p0_.push_back(data.exp_a[g]);
        p1_.push_back(data.exp_b[g]);
        p2_.push_back(data.exp_c[g]);
        p3_.push_back(data.exp_d[g]);
      }
      break;
    case Family::kQuadratic:
      p0_.resize(m * q);
      p1_.resize(m * q);
      for (std::size_t v = 0; v < m; ++v)
        for (std::size_t k = 0; k < q; ++k) {
          p0_[v * q + k] = data.quad_h[static_cast<std::size_t>(nodes_[v]) * q + k];
          p1_[v * q + k] = data.quad_r[static_cast<std::size_t>(nodes_[v]) * q + k];
        }
      break;
    case Family::kLogistic:
    case Family::kLeastSquares: {
      // Samples grouped by local node, in file order within a node.
      std::vector<std::int64_t> local(static_cast<std::size_t>(n_global_), -1);
      for (std::size_t v = 0; v < m; ++v) local[nodes_[v]] = static_cast<std::int64_t>(v);
      sample_begin_.assign(m + 1, 0);
      for (GlobalId o : data.owner)
        if (local[o] >= 0) ++sample_begin_[local[o] + 1];
      for (std::size_t v = 0; v < m; ++v) sample_begin_[v + 1] += sample_begin_[v];
      features_.resize(static_cast<std::size_t>(sample_begin_[m]) * q);
      labels_.resize(static_cast<std::size_t>(sample_begin_[m]));
      std::vector<std::int64_t> fill(sample_begin_.begin(), sample_begin_.end() - 1);
      for (std::size_t s = 0; s < data.owner.size(); ++s) {
        const std::int64_t v = local[data.owner[s]];
        if (v < 0) continue;
        const std::int64_t pos = fill[v]++;
        labels_[pos] = data.labels[s];
        std::memcpy(&features_[pos * q], &data.features[s * q], q * sizeof(double));
      }
      break;
    }
  }
}

double LocalObjectives::value(LocalId v, const double* x) const {
  const int q = dim_;
  switch (family_) {
    case Family::kExp:
      return p0_[v] * std::exp(p1_[v] * x[0]) + p2_[v] * std::exp(-p3_[v] * x[0]);
    case Family::kQuadratic: {
      double f = 0;
      for (int k = 0; k < q; ++k) {
        const double t = x[k] - p1_[v * q + k];
        f += 0.5 * p0_[v * q + k] * t * t;
      }
      return f;
    }
    case Family::kLogistic: {
      double f = 0.5 * lambda_ / static_cast<double>(n_global_) * dot(x, x, q);
      for (std::int64_t s = sample_begin_[v]; s < sample_begin_[v + 1]; ++s)
        f += softplus(-labels_[s] * dot(&features_[s * q], x, q));
      return f;
    }
    case Family::kLeastSquares: {
      double f = 0.5 * lambda_ / static_cast<double>(n_global_) * dot(x, x, q);
      for (std::int64_t s = sample_begin_[v]; s < sample_begin_[v + 1]; ++s) {
        const double r = dot(&features_[s * q], x, q) - labels_[s];
        f += r * r;
      }
      return f;
    }
  }
  return 0;
}

void LocalObjectives::gradient(LocalId v, const double* x, double* g) const {
  const int q = dim_;
  switch (family_) {
    case Family::kExp:
      g[0] = p0_[v] * p1_[v] * std::exp(p1_[v] * x[0]) - p2_[v] * p3_[v] * std::exp(-p3_[v] * x[0]);
      return;
    case Family::kQuadratic:
      for (int k = 0; k < q; ++k) g[k] = p0_[v * q + k] * (x[k] - p1_[v * q + k]);
      return;
    case Family::kLogistic: {
      const double reg = lambda_ / static_cast<double>(n_global_);
      for (int k = 0; k < q; ++k) g[k] = reg * x[k];
      // d/dx log(1 + e^(-y a.x)) = -y sigmoid(-y a.x) a
      for (std::int64_t s = sample_begin_[v]; s < sample_begin_[v + 1]; ++s) {
        const double* a = &features_[s * q];
        const double y = labels_[s];
        const double w = -y * sigmoid(-y * dot(a, x, q));
        for (int k = 0; k < q; ++k) g[k] += w * a[k];
      }
      return;
    }
    case Family::kLeastSquares: {
      const double reg = lambda_ / static_cast<double>(n_global_);
      for (int k = 0; k < q; ++k) g[k] = reg * x[k];
      // d/dx (a.x - b)^2 = 2 (a.x - b) a
      for (std::int64_t s = sample_begin_[v]; s < sample_begin_[v + 1]; ++s) {
        const double* a = &features_[s * q];
        const double w = 2.0 * (dot(a, x, q) - labels_[s]);
        for (int k = 0; k < q; ++k) g[k] += w * a[k];
      }
      return;
    }
  }
}

void LocalObjectives::hessian(LocalId v, const double* x, double* h) const {
  const int q = dim_;
  switch (family_) {
    case Family::kExp: {
      const double b = p1_[v], d = p3_[v];
      h[0] = p0_[v] * b * b * std::exp(b * x[0]) + p2_[v] * d * d * std::exp(-d * x[0]);
      return;
    }
    case Family::kQuadratic:
      for (int i = 0; i < q * q; ++i) h[i] = 0;
      for (int k = 0; k < q; ++k) h[k * q + k] = p0_[v * q + k];
      return;
    case Family::kLogistic: {
      const double reg = lambda_ / static_cast<double>(n_global_);
      for (int i = 0; i < q * q; ++i) h[i] = 0;
      for (int k = 0; k < q; ++k) h[k * q + k] = reg;
      // d^2/dx^2 log(1 + e^(-t)) with t = y a.x: sigmoid(t) sigmoid(-t) a a^T (y^2 = 1)
      for (std::int64_t s = sample_begin_[v]; s < sample_begin_[v + 1]; ++s) {
        const double* a = &features_[s * q];
        const double t = labels_[s] * dot(a, x, q);
        const double w = sigmoid(t) * sigmoid(-t);
        for (int i = 0; i < q; ++i)
          for (int k = i; k < q; ++k) h[i * q + k] += w * a[i] * a[k];
      }
      for (int i = 0; i < q; ++i)  // mirrored, so that the matrix is exactly symmetric
        for (int k = 0; k < i; ++k) h[i * q + k] = h[k * q + i];
      return;
    }
    case Family::kLeastSquares: {
      const double reg = lambda_ / static_cast<double>(n_global_);
      for (int i = 0; i < q * q; ++i) h[i] = 0;
      for (int k = 0; k < q; ++k) h[k * q + k] = reg;
      for (std::int64_t s = sample_begin_[v]; s < sample_begin_[v + 1]; ++s) {  // 2 a a^T, independent of x
        const double* a = &features_[s * q];
        for (int i = 0; i < q; ++i)
          for (int k = i; k < q; ++k) h[i * q + k] += 2.0 * a[i] * a[k];
      }
      for (int i = 0; i < q; ++i)
        for (int k = 0; k < i; ++k) h[i * q + k] = h[k * q + i];
      return;
    }
  }
}

}  // namespace snl::consensus

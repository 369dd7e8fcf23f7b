// Distributed Newton method on a spanning tree (001 Alg. 2) or a Hamilton path
// (Alg. 1): minimise sum_p f_p(x_p) subject to x_c = x_parent(c) on the tree's
// links. Newton step from the KKT system with H = blockdiag(grad^2 f_p):
//   dx = -H^-1 (g + A^T w),   (A H^-1 A^T) w = A x - A H^-1 g,
// where link l = (c, parent(c)) has row +I at c and -I at the parent, and its
// dual w_l (q reals) is owned by the child c. The dual is solved either by
// Wei-Ozdaglar-Jadbabaie's matrix splitting M = A H^-1 A^T = D + B,
//   w(t+1) = (D + Bbar)^-1 ((Bbar - B) w(t) + rhs) = w(t) + (D + Bbar)^-1 (rhs - M w(t)),
// Bbar_ii = sum_j |B_ij| (a link only needs the links that share an end node),
// by preconditioned conjugate gradients (neighbour messages and one allreduce
// per iteration, an inexact-Newton forcing term tied to the decrement),
// or exactly by one leaf-to-root and one root-to-leaf sweep. Primal step by
// Armijo backtracking on the Lagrangian (F on feasible iterates), one convergecast per trial,
// or damped as in Wei-Ozdaglar-Jadbabaie (primal_step, solver_detail.hpp).
#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <utility>

#include "consensus/solver_detail.hpp"
#include "core/exact_sum.hpp"
#include "snl/core/mpi_util.hpp"

namespace snl::consensus::detail {

namespace {

// Link l = (c, P): rhs_l = (x_c - x_P) - (u_c - u_P) with u = H^-1 g (the row l
// of A x - A H^-1 g), and 1 / (D + Bbar)_l. Row k of M's block row l: the
// diagonal block Hinv_c + Hinv_P, then -/+ Hinv_c for each of the deg_c - 1
// other links at c and -/+ Hinv_P for each of the deg_P - 1 other links at P.
// Both ends of a link call this with the same numbers (the same bits).
void link_coeffs(int q, const double* xc, const double* uc, const double* hic, double degc, const double* xp,
                 const double* up, const double* hip, double degp, double* rhs, double* dinv) {
  for (int k = 0; k < q; ++k) {
    rhs[k] = (xc[k] - xp[k]) - (uc[k] - up[k]);
    double bbar = 0, rc = 0, rp = 0;
    for (int j = 0; j < q; ++j) {
      if (j != k) bbar += std::fabs(hic[k * q + j] + hip[k * q + j]);
      rc += std::fabs(hic[k * q + j]);
      rp += std::fabs(hip[k * q + j]);
    }
    bbar += (degc - 1) * rc + (degp - 1) * rp;
    dinv[k] = 1.0 / ((hic[k * q + k] + hip[k * q + k]) + bbar);
  }
}

class Newton final : public Runner {
 public:
  Newton(MPI_Comm comm, const ProblemData& data, const SolveOptions& opt, std::unique_ptr<Tree> tree)
      : comm_(comm), opt_(opt), tree_(std::move(tree)), q_(data.dim), n_(data.num_nodes) {
    const DistGraph& g = tree_->graph();
    std::vector<GlobalId> owned(g.local_to_global().begin(), g.local_to_global().begin() + g.num_owned());
    obj_ = LocalObjectives(data, owned);
    gather_ = NodeGather(comm, n_, owned);
    const LocalId nl = g.num_local(), no = g.num_owned();
    const std::size_t q = q_, qq = q * q, nnz = g.adjacency().size();
    pw_ = 3 * q_ + q_ * q_ + 1;
    x_.assign(nl * q, 0.0);  // x(0) = 0 at every node
    w_.assign(no * q, 0.0);
    grad_.assign(no * q, 0.0);
    hess_.assign(no * qq, 0.0);
    pk_.assign(nl * pw_, 0.0);
    lrhs_.assign(nnz * q, 0.0);
    ldinv_.assign(nnz * q, 0.0);
    wnew_.assign(nnz * q, 0.0);
    e_[0].assign(nl * 2 * q, 0.0);
    e_[1].assign(nl * 2 * q, 0.0);
    dx_.assign(no * q, 0.0);
    up_.assign(nl * (q + qq), 0.0);
    work_.assign(qq, 0.0);
    tmp_.assign(q, 0.0);
    one_.assign(nl, 0.0);
    z_.assign(q, 0.0);
    for (auto* v : {&cg_w_, &cg_y_}) v->assign(nl * q, 0.0);
    for (auto* v : {&cg_rhs_, &cg_r_, &cg_z_, &cg_az_, &cg_p_, &cg_s_}) v->assign(no * q, 0.0);
    cg_dinv_.assign(no * qq, 0.0);
    cg_d_.assign(qq, 0.0);
    xdx_.assign(nl * 2 * q, 0.0);
  }

  std::int32_t tree_depth() const override { return tree_->depth(); }

  bool iterate(std::int64_t, Counters& c) override {
    if (!local_derivatives()) return fail();
    if (opt_.dual_kind() == DualSolver::kExact) {
      if (!exact_dual(c)) return fail();
    } else if (opt_.dual_kind() == DualSolver::kCg) {
      if (!cg_dual(c)) return fail();
    } else {
      splitting_dual(c);
    }
    theta_ = decrement(c);
    if (!std::isfinite(theta_)) return false;
    step_ = primal_step(opt_, theta_, c, [&](double t) { return objective_along(t, c); });
    if (!std::isfinite(step_)) return false;
    const LocalId no = tree_->num_owned();
    for (std::int64_t i = 0; i < std::int64_t(no) * q_; ++i) x_[i] += step_ * dx_[i];
    return true;
  }

  bool converged(double tol, const HistoryRecord&) const override { return theta_ <= tol; }

  void measure(std::int64_t, const std::vector<double>& xstar, HistoryRecord& r) override {
    r.max_abs_error = max_abs_error(comm_, x_.data(), tree_->num_owned(), xstar);
    r.objective = objective_at_average(gather_, obj_, n_, x_.data());
    r.avg_max_abs_error = r.avg_objective = NAN;
    r.decrement = theta_;
    r.step = step_;
  }

  std::vector<double> x_rows() const override { return gather_.to_root(x_.data(), q_); }
  void set_x_rows(const std::vector<double>& all) override { gather_.pick(all, q_, x_.data()); }
  std::vector<double> dual_rows() const override { return gather_.to_all(w_.data(), q_); }

  void save(H5File& f) const override {
    write_node_rows(f, "state/x", gather_, n_, x_.data(), q_);
    write_node_rows(f, "state/w", gather_, n_, w_.data(), q_);
    f.write_scalar("state/theta", theta_);
    f.write_scalar("state/step", step_);
  }
  void load(const H5File& f) override {
    read_node_rows(f, "state/x", gather_, n_, x_.data(), q_);
    read_node_rows(f, "state/w", gather_, n_, w_.data(), q_);
    theta_ = f.read_scalar("state/theta");
    step_ = f.read_scalar("state/step");
  }

 private:
  bool fail() {
    theta_ = NAN;
    return false;
  }

  // g_v, H_v, H_v^-1 and u_v = H_v^-1 g_v of the owned nodes at x; packet rows.
  bool local_derivatives() {
    const LocalId no = tree_->num_owned();
    const int q = q_, qq = q * q;
    int bad = 0;
    for (LocalId v = 0; v < no; ++v) {
      double* pk = &pk_[std::size_t(v) * pw_];
      const double* xv = &x_[std::size_t(v) * q];
      obj_.gradient(v, xv, &grad_[std::size_t(v) * q]);
      obj_.hessian(v, xv, &hess_[std::size_t(v) * qq]);
      double* hinv = pk + 3 * q;
      if (!spd_inverse(q, &hess_[std::size_t(v) * qq], hinv, work_.data())) bad = 1;
      std::copy(xv, xv + q, pk);
      matvec(q, hinv, &grad_[std::size_t(v) * q], pk + q);
      std::copy(&w_[std::size_t(v) * q], &w_[std::size_t(v) * q] + q, pk + 2 * q);
      pk[3 * q + qq] = tree_->tree_degree(v);
    }
    int any = 0;
    MPI_Allreduce(&bad, &any, 1, MPI_INT, MPI_MAX, comm_);
    return any == 0;
  }

  // The splitting iteration, warm-started from the previous Newton step's w.
  // One halo exchange per dual iteration carries (w_v, y_v), y_v = H_v^-1
  // (A^T w)_v = H_v^-1 (w_v - sum_children w_c): then M w on link (c, P) is
  // y_c - y_P, and a node updates its own link and (redundantly, with the
  // child's numbers) its children's links, so it knows its children's new w
  // for y_v(t+1) without a second exchange.
  void splitting_dual(Counters& c) {
    DistGraph& g = tree_->graph();
    const int q = q_;
    const LocalId no = g.num_owned();
    const double links = double(n_ - 1);
    // Static data of this Newton step to the tree neighbours: x, u, w(0), H^-1, degree.
    g.halo().exchange(pk_.data(), pw_);
    c.add(2 * links, pw_);
    const auto& off = g.offsets();
    const auto& adj = g.adjacency();
    for (LocalId v = 0; v < no; ++v)
      for (auto e = off[v]; e < off[v + 1]; ++e) {
        const bool own = e == tree_->parent_entry(v);
        const double* pc = &pk_[std::size_t(own ? v : adj[e]) * pw_];
        const double* pp = &pk_[std::size_t(own ? adj[e] : v) * pw_];
        link_coeffs(q, pc, pc + q, pc + 3 * q, pc[3 * q + q * q], pp, pp + q, pp + 3 * q, pp[3 * q + q * q],
                    &lrhs_[e * q], &ldinv_[e * q]);
      }
    // w(0), y(0).
    int cur = 0;
    for (LocalId v = 0; v < no; ++v) {
      double* ev = &e_[cur][std::size_t(v) * 2 * q];
      std::copy(&w_[std::size_t(v) * q], &w_[std::size_t(v) * q] + q, ev);
      node_y(v, ev, [&](std::int64_t e) { return &pk_[std::size_t(adj[e]) * pw_ + 2 * q]; });
    }
    std::int64_t t = 0;
    for (; t < opt_.dual_max_iterations();) {
      g.halo().exchange(e_[cur].data(), 2 * q);
      c.add(2 * links, 2 * q);
      double loc[2] = {0, 0};
      const int nxt = 1 - cur;
      for (LocalId v = 0; v < no; ++v) {
        const double* ev = &e_[cur][std::size_t(v) * 2 * q];
        for (auto e = off[v]; e < off[v + 1]; ++e) {
          const bool own = e == tree_->parent_entry(v);
          const double* lc = &e_[cur][std::size_t(own ? v : adj[e]) * 2 * q];  // the link's child end
          const double* yp = &e_[cur][std::size_t(own ? adj[e] : v) * 2 * q] + q;
          for (int k = 0; k < q; ++k)
            wnew_[e * q + k] = lc[k] + ldinv_[e * q + k] * (lrhs_[e * q + k] - (lc[q + k] - yp[k]));
        }
        double* en = &e_[nxt][std::size_t(v) * 2 * q];
        const auto pe = tree_->parent_entry(v);
        for (int k = 0; k < q; ++k) {
          en[k] = pe >= 0 ? wnew_[pe * q + k] : 0.0;
          loc[0] = std::max(loc[0], std::fabs(en[k] - ev[k]));
          loc[1] = std::max(loc[1], std::fabs(en[k]));
        }
        node_y(v, en, [&](std::int64_t e) { return &wnew_[e * q]; });
      }
      cur = nxt;
      ++t;
      // Global test (a max: exact in any order), as a convergecast and a broadcast.
      double glob[2];
      MPI_Allreduce(loc, glob, 2, MPI_DOUBLE, MPI_MAX, comm_);
      c.add(2 * links, 2);
      if (glob[0] <= opt_.dual_tolerance() * glob[1]) break;
    }
    c.dual_iterations += t;
    for (LocalId v = 0; v < no; ++v) {
      const double* ev = &e_[cur][std::size_t(v) * 2 * q];
      for (int k = 0; k < q; ++k) {
        w_[std::size_t(v) * q + k] = ev[k];
        dx_[std::size_t(v) * q + k] = -(pk_[std::size_t(v) * pw_ + q + k] + ev[q + k]);
      }
    }
  }

  // M w = A H^-1 A^T w on the tree's links, w given on the owned links (the
  // root's row ignored): y_v = H_v^-1 (w_v - sum of the children's w, in
  // global-id order), then (M w)_c = y_c - y_parent(c). Two neighbour
  // exchanges: w up to the parents, y down to the children.
  void dual_matvec(const double* w, double* mw, Counters& c) {
    DistGraph& g = tree_->graph();
    const int q = q_;
    const LocalId no = g.num_owned();
    const auto& off = g.offsets();
    const auto& adj = g.adjacency();
    for (LocalId v = 0; v < no; ++v)
      for (int k = 0; k < q; ++k)
        cg_w_[std::size_t(v) * q + k] = tree_->parent_entry(v) >= 0 ? w[std::size_t(v) * q + k] : 0.0;
    g.halo().exchange(cg_w_.data(), q);
    c.add(double(n_ - 1), q);
    for (LocalId v = 0; v < no; ++v) {
      for (int k = 0; k < q; ++k) tmp_[k] = cg_w_[std::size_t(v) * q + k];
      for (auto e = off[v]; e < off[v + 1]; ++e) {
        if (e == tree_->parent_entry(v)) continue;
        for (int k = 0; k < q; ++k) tmp_[k] -= cg_w_[std::size_t(adj[e]) * q + k];
      }
      matvec(q, &pk_[std::size_t(v) * pw_ + 3 * q], tmp_.data(), &cg_y_[std::size_t(v) * q]);
    }
    g.halo().exchange(cg_y_.data(), q);
    c.add(double(n_ - 1), q);
    if (!mw) return;
    for (LocalId v = 0; v < no; ++v) {
      const auto pe = tree_->parent_entry(v);
      for (int k = 0; k < q; ++k)
        mw[std::size_t(v) * q + k] =
            pe >= 0 ? cg_y_[std::size_t(v) * q + k] - cg_y_[std::size_t(adj[pe]) * q + k] : 0.0;
    }
  }

  // Exact sums over the owned links of a_l . b_l (pairs[i] = (a, b)), in one
  // allreduce: the same bits on any number of ranks. Counted as a convergecast
  // and a broadcast on the tree.
  void link_dots(std::initializer_list<std::pair<const double*, const double*>> pairs, double* out, Counters& c) {
    snl::detail::ExactSum sums[3];
    const LocalId no = tree_->num_owned();
    for (LocalId v = 0; v < no; ++v) {
      if (tree_->parent_entry(v) < 0) continue;
      int i = 0;
      for (const auto& ab : pairs) {
        for (int k = 0; k < q_; ++k) sums[i].add(ab.first[std::size_t(v) * q_ + k] * ab.second[std::size_t(v) * q_ + k]);
        ++i;
      }
    }
    const int n = static_cast<int>(pairs.size());
    snl::detail::allreduce_exact(sums, n, comm_);
    for (int i = 0; i < n; ++i) out[i] = sums[i].value();
    c.add(2 * double(n_ - 1), n);
  }

  // The dual by preconditioned CG (Chronopoulos-Gear: one allreduce per
  // iteration) with the block-Jacobi preconditioner (H_c^-1 + H_P^-1)^-1 of
  // each link, warm-started from the previous step's w. The residual
  // r = rhs - M w is the infeasibility A (x + dx) that the step leaves, and
  // the next step starts from it. Inexact Newton: CG stops when
  // ||r|| <= eta ||r(0)||, eta = max(dual_tol, min(0.1, theta of the
  // previous step)): every step cuts the infeasibility at least tenfold,
  // and the last ones to the noise. A dual iteration is one product with M.
  bool cg_dual(Counters& c) {
    DistGraph& g = tree_->graph();
    const int q = q_, qq = q * q;
    const LocalId no = g.num_owned();
    g.halo().exchange(pk_.data(), pw_);  // x, u, w, H^-1, degree to the tree neighbours
    c.add(2 * double(n_ - 1), pw_);
    const auto& adj = g.adjacency();
    int bad = 0;
    for (LocalId v = 0; v < no; ++v) {
      const auto pe = tree_->parent_entry(v);
      double* r = &cg_rhs_[std::size_t(v) * q];
      double* dinv = &cg_dinv_[std::size_t(v) * qq];
      if (pe < 0) {
        std::fill(r, r + q, 0.0);
        std::fill(dinv, dinv + qq, 0.0);
        continue;
      }
      const double* pc = &pk_[std::size_t(v) * pw_];
      const double* pp = &pk_[std::size_t(adj[pe]) * pw_];
      for (int k = 0; k < q; ++k) r[k] = (pc[k] - pp[k]) - (pc[q + k] - pp[q + k]);
      for (int k = 0; k < qq; ++k) cg_d_[k] = pc[3 * q + k] + pp[3 * q + k];
      if (!spd_inverse(q, cg_d_.data(), dinv, work_.data())) bad = 1;
    }
    int any = 0;
    MPI_Allreduce(&bad, &any, 1, MPI_INT, MPI_MAX, comm_);
    if (any) return false;
    const double eta =
        std::max(opt_.dual_tolerance(), std::min(0.1, std::isfinite(theta_) ? theta_ : INFINITY));
    const std::size_t m = std::size_t(no) * q;
    double* w = w_.data();
    auto precondition = [&] {
      for (LocalId v = 0; v < no; ++v)
        matvec(q, &cg_dinv_[std::size_t(v) * qq], &cg_r_[std::size_t(v) * q], &cg_z_[std::size_t(v) * q]);
    };
    dual_matvec(w, cg_az_.data(), c);  // M w(0)
    for (std::size_t i = 0; i < m; ++i) cg_r_[i] = cg_rhs_[i] - cg_az_[i];
    precondition();
    dual_matvec(cg_z_.data(), cg_az_.data(), c);
    double d3[3];
    link_dots({{cg_r_.data(), cg_z_.data()}, {cg_az_.data(), cg_z_.data()}, {cg_r_.data(), cg_r_.data()}}, d3, c);
    double gamma = d3[0], delta = d3[1], rr = d3[2];
    const double bound = eta * eta * rr;
    double alpha = gamma / delta, beta = 0;
    std::fill(cg_p_.begin(), cg_p_.end(), 0.0);
    std::fill(cg_s_.begin(), cg_s_.end(), 0.0);
    std::int64_t t = 2;  // products with M so far
    while (rr > bound && gamma > 0 && delta > 0 && t < opt_.dual_max_iterations()) {
      for (std::size_t i = 0; i < m; ++i) {
        cg_p_[i] = cg_z_[i] + beta * cg_p_[i];
        cg_s_[i] = cg_az_[i] + beta * cg_s_[i];
        w[i] += alpha * cg_p_[i];
        cg_r_[i] -= alpha * cg_s_[i];
      }
      precondition();
      dual_matvec(cg_z_.data(), cg_az_.data(), c);
      ++t;
      link_dots({{cg_r_.data(), cg_z_.data()}, {cg_az_.data(), cg_z_.data()}, {cg_r_.data(), cg_r_.data()}}, d3, c);
      const double gamma_new = d3[0];
      delta = d3[1];
      rr = d3[2];
      beta = gamma_new / gamma;
      alpha = gamma_new / (delta - beta * gamma_new / alpha);
      gamma = gamma_new;
    }
    c.dual_iterations += t;
    // dx_v = -(u_v + y_v) with y = H^-1 A^T w of the final w (w's exchange up only).
    dual_matvec(w, nullptr, c);
    for (LocalId v = 0; v < no; ++v)
      for (int k = 0; k < q; ++k)
        dx_[std::size_t(v) * q + k] = -(pk_[std::size_t(v) * pw_ + q + k] + cg_y_[std::size_t(v) * q + k]);
    for (LocalId v = 0; v < no; ++v)
      if (tree_->parent_entry(v) < 0) std::fill(&w_[std::size_t(v) * q], &w_[std::size_t(v) * q] + q, 0.0);
    return std::isfinite(rr);
  }

  // y_v = H_v^-1 (w_v - sum over children c, in global-id order, of w_c), with
  // ev = (w_v, y_v) and child_w(e) the child's w at adjacency entry e.
  template <class ChildW>
  void node_y(LocalId v, double* ev, ChildW&& child_w) {
    const int q = q_;
    const auto& off = tree_->graph().offsets();
    for (int k = 0; k < q; ++k) tmp_[k] = ev[k];
    for (auto e = off[v]; e < off[v + 1]; ++e) {
      if (e == tree_->parent_entry(v)) continue;
      const double* wc = child_w(e);
      for (int k = 0; k < q; ++k) tmp_[k] -= wc[k];
    }
    matvec(q, &pk_[std::size_t(v) * pw_ + 3 * q], tmp_.data(), ev + q);
  }

  // The exact dual of the tree: the exact Newton step makes every copy equal
  // z = (sum_p H_p)^-1 sum_p (H_p x_p - g_p) (the link rows of A (x + dx) = 0
  // and sum_p (A^T w)_p = 0); the dual of link (v, parent) is the sum over v's
  // subtree of H_p (x_p - z) - g_p. One convergecast of (H x - g, H), one
  // broadcast of z.
  bool exact_dual(Counters& c) {
    const int q = q_, qq = q * q, w = q + qq;
    const LocalId no = tree_->num_owned();
    for (LocalId v = 0; v < no; ++v) {
      double* row = &up_[std::size_t(v) * w];
      const double* h = &hess_[std::size_t(v) * qq];
      matvec(q, h, &x_[std::size_t(v) * q], row);
      for (int k = 0; k < q; ++k) row[k] -= grad_[std::size_t(v) * q + k];
      std::copy(h, h + qq, row + q);
    }
    tree_->up_sum(up_.data(), w);
    const double links = double(n_ - 1);
    c.add(links, w);
    // z at the root, then to every node: a broadcast down the tree copies the
    // root's value unchanged, so MPI_Bcast does it (counted as the tree's n-1 messages).
    int bad = 0;
    const LocalId r = tree_->root_local();
    if (r >= 0) {
      const double* row = &up_[std::size_t(r) * w];
      if (!spd_solve(q, row + q, row, z_.data(), work_.data())) bad = 1;
    }
    MPI_Bcast(&bad, 1, MPI_INT, tree_->root_rank(), comm_);
    if (bad) return false;
    MPI_Bcast(z_.data(), q, MPI_DOUBLE, tree_->root_rank(), comm_);
    c.add(links, q);
    c.dual_iterations += 1;
    for (LocalId v = 0; v < no; ++v) {
      const double* z = z_.data();
      const double* row = &up_[std::size_t(v) * w];
      matvec(q, row + q, z, tmp_.data());
      for (int k = 0; k < q; ++k) {
        w_[std::size_t(v) * q + k] = tree_->parent_entry(v) >= 0 ? row[k] - tmp_[k] : 0.0;
        dx_[std::size_t(v) * q + k] = z[k] - x_[std::size_t(v) * q + k];
      }
    }
    return true;
  }

  // The line search's merit at x + t dx: the Lagrangian
  //   L(x, w) = sum_p f_p(x_p) + sum over links (c, P) of w_c . (x_c - x_P)
  // with the step's duals w, whose slope along dx is (g + A^T w) . dx =
  // -dx^T H dx = -theta^2 for any w: the Armijo test holds what it promises
  // even when an inexact dual leaves the copies apart (then F alone can rise
  // along dx, as the copies are pulled together). On feasible iterates (the
  // exact dual) L = F. At t = 0 the parents' x and dx come to their children
  // (one message of 2q reals per link); each value is a convergecast of L and
  // a broadcast of the total.
  double objective_along(double t, Counters& c) {
    const int q = q_;
    const LocalId no = tree_->num_owned();
    if (t == 0.0) {
      for (LocalId v = 0; v < no; ++v)
        for (int k = 0; k < q; ++k) {
          xdx_[std::size_t(v) * 2 * q + k] = x_[std::size_t(v) * q + k];
          xdx_[std::size_t(v) * 2 * q + q + k] = dx_[std::size_t(v) * q + k];
        }
      tree_->graph().halo().exchange(xdx_.data(), 2 * q);
      c.add(double(n_ - 1), 2 * q);
    }
    const auto& adj = tree_->graph().adjacency();
    for (LocalId v = 0; v < no; ++v) {
      const double* mine = &xdx_[std::size_t(v) * 2 * q];
      for (int k = 0; k < q; ++k) tmp_[k] = mine[k] + t * mine[q + k];
      one_[v] = obj_.value(v, tmp_.data());
      const auto pe = tree_->parent_entry(v);
      if (pe < 0) continue;
      const double* par = &xdx_[std::size_t(adj[pe]) * 2 * q];
      for (int k = 0; k < q; ++k)
        one_[v] += w_[std::size_t(v) * q + k] * ((mine[k] + t * mine[q + k]) - (par[k] + t * par[q + k]));
    }
    return tree_total(c);
  }

  // The sum of one_ over the tree, on every rank: a convergecast and a broadcast.
  double tree_total(Counters& c) {
    tree_->up_sum(one_.data(), 1);
    c.add(2 * double(n_ - 1), 1);
    double total = tree_->root_local() >= 0 ? one_[tree_->root_local()] : 0.0;
    MPI_Bcast(&total, 1, MPI_DOUBLE, tree_->root_rank(), comm_);
    return total;
  }

  // theta^2 = sum_p dx_p^T H_p dx_p by a convergecast over the tree (children
  // in global-id order: the same bits on any number of ranks), then a broadcast.
  double decrement(Counters& c) {
    const int q = q_, qq = q * q;
    const LocalId no = tree_->num_owned();
    for (LocalId v = 0; v < no; ++v)
      one_[v] = quad_form(q, &hess_[std::size_t(v) * qq], &dx_[std::size_t(v) * q]);
    const double t2 = tree_total(c);
    return (t2 >= 0 && std::isfinite(t2)) ? std::sqrt(t2) : NAN;
  }

  MPI_Comm comm_;
  SolveOptions opt_;
  std::unique_ptr<Tree> tree_;
  int q_;
  GlobalId n_;
  int pw_ = 0;
  LocalObjectives obj_;
  NodeGather gather_;
  std::vector<double> x_, w_, grad_, hess_, pk_, lrhs_, ldinv_, wnew_, e_[2], dx_, up_, work_, tmp_, one_, z_;
  std::vector<double> cg_w_, cg_y_;  // [local * q] with ghosts: w and y = H^-1 A^T w for dual_matvec
  std::vector<double> cg_rhs_, cg_r_, cg_z_, cg_az_, cg_p_, cg_s_, cg_dinv_, cg_d_;
  std::vector<double> xdx_;  // [local * 2q] (x, dx) with the ghosts: the line search's merit  // [owned * q], dinv [owned * q * q]
  double theta_ = NAN, step_ = 0;
};

}  // namespace

std::unique_ptr<Runner> make_newton(MPI_Comm comm, const ProblemData& data, const SolveOptions& opt,
                                    std::unique_ptr<Tree> tree) {
  return std::make_unique<Newton>(comm, data, opt, std::move(tree));
}

}  // namespace snl::consensus::detail

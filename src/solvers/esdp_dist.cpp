// The edge-based SDP relaxation (ESDP) solved by a distributed method, as 003
// compares Algorithm 1 against Simonetto and Leus' distributed ESDP (003
// Sec. V-B, Fig. 6, Table II). The relaxation is the one `--algorithm esdp`
// solves centrally (centralized/relaxations.hpp): each ML term
// (||x_i - x_j|| - d)^2 / 2 lifted to (D - 2 d delta + d^2) / 2 with
// [1 delta; delta D] >= 0 and D the lifted squared distance of the
// (p+2)x(p+2) edge block [I x_i x_j; x_i' Y_ii Y_ij; x_j' Y_ij Y_jj] >= 0.
//
// The distributed method is consensus ADMM with projections (the project's
// formulation; docs/esdp-dist.md gives it in full and says where Simonetto and
// Leus differ):
//  - one PSD block per measurement: a sensor edge's block S_e of order p+3 is
//    the edge block bordered by a column m_e and a 1 ([M m; m' 1] >= 0 holds
//    exactly when M >= 0 and delta^2 <= D(M) for delta = u'm, so both of the
//    ESDP's cones of that measurement are one cone); an anchor measurement's
//    block of order p+2 borders the node block [I x_i; x_i' Y_ii] the same way;
//  - the cost is linear in each block: <C_e, S_e> + const;
//  - the consensus variables v: x_i and Y_ii of each sensor (shared by the
//    blocks of its measurements), the constants I and 1, and each block's own
//    entries (Y_ij and the border m_e);
//  - one iteration (scaled ADMM, penalty rho, Frobenius norm on the blocks):
//      U_b <- U_b + S_b - E_b(v)                    (dual step of the last iteration)
//      S_b <- P_psd(E_b(v) - U_b - C_b / rho)       (eigen-decomposition of the block)
//      v   <- the average over the blocks that hold a variable of (S_b + U_b);
//  - every sensor computes the blocks of all its measurements, so the two ends
//    of a sensor edge compute the same block from the same numbers (the block
//    is laid out with the smaller global id first, so they agree bit for bit)
//    and the only exchange is each sensor's (x_i, Y_ii): one message of p+1
//    reals per sensor per iteration.
// Every node sums its blocks in global-id order, so iterates are bit-identical
// for any number of ranks.
#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

#include "core/exact_sum.hpp"
#include "solvers/algorithm_util.hpp"
#include "solvers/methods.hpp"

namespace snl {

namespace {

constexpr int kMaxOrder = 6;  // p + 3 for p <= 3: blocks live on the stack
using Mat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxOrder, kMaxOrder>;
using BlockVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxOrder, 1>;

class EsdpDist final : public Algorithm {
 public:
  EsdpDist(LocalizationProblem& prob, double rho) : prob_(prob), rho_(rho), p_(prob.dim()) {
    if (p_ < 1 || p_ + 3 > kMaxOrder) throw Error("--algorithm esdp-dist supports dimension 1 to 3");
  }
  std::string name() const override { return algorithm_info(AlgorithmId::kEsdpDist).name; }
  // Each sensor broadcasts (x_i, Y_ii) once per iteration.
  double messages_per_iteration() const override { return 1.0; }
  double reals_per_iteration() const override { return p_ + 1.0; }

  void start(const std::vector<double>& x0) override {
    const auto& gr = prob_.graph();
    const LocalId nl = prob_.num_local(), no = prob_.num_owned();
    x_ = detail::with_ghost_rows(prob_, x0);
    yd_.assign(std::size_t(nl), 0.0);
    for (LocalId v = 0; v < no; ++v) yd_[v] = row(x_.data(), v).squaredNorm();
    exchange();
    x_old_.assign(x_.begin(), x_.begin() + std::size_t(no) * p_);
    xn_.assign(std::size_t(no) * p_, 0.0);
    yn_.assign(std::size_t(no), 0.0);
    const std::size_t qe = std::size_t(p_ + 3) * (p_ + 3), qa = std::size_t(p_ + 2) * (p_ + 2);
    const std::size_t ne = gr.adjacency().size(), na = prob_.anchor_ranges().size();
    es_.assign(ne * qe, 0.0), eu_.assign(ne * qe, 0.0), ev_.assign(ne * qe, 0.0);
    as_.assign(na * qa, 0.0), au_.assign(na * qa, 0.0), av_.assign(na * qa, 0.0);
    // The blocks' own entries start at the rank-p lifting of x0 (Y_ij = x_i'x_j) and m = 0.
    for (LocalId v = 0; v < no; ++v)
      for (auto e = gr.offsets()[v]; e < gr.offsets()[v + 1]; ++e) {
        const LocalId u = gr.adjacency()[e];
        const double yij = row(x_.data(), v).dot(row(x_.data(), u));
        ev_[std::size_t(e) * qe + std::size_t(p_) * (p_ + 3) + p_ + 1] = yij;  // (p+1, p), column-major
        ev_[std::size_t(e) * qe + std::size_t(p_ + 1) * (p_ + 3) + p_] = yij;  // (p, p+1)
      }
    k_ = 0;
  }

  void iterate() override {
    exchange();  // ghosts' (x_j, Y_jj) of v(k)
    const auto& gr = prob_.graph();
    for (LocalId v = 0; v < prob_.num_owned(); ++v) {
      BlockVec acc = BlockVec::Zero(p_ + 1);
      int cnt = 0;
      for (auto e = gr.offsets()[v]; e < gr.offsets()[v + 1]; ++e, ++cnt) acc += edge_step(v, e);
      for (auto t = prob_.anchor_offsets()[v]; t < prob_.anchor_offsets()[v + 1]; ++t, ++cnt)
        acc += anchor_step(v, t);
      if (cnt > 0) acc /= cnt;  // a sensor without measurements keeps its x0 (the ESDP leaves it free)
      for (int c = 0; c < p_; ++c) xn_[std::size_t(v) * p_ + c] = cnt > 0 ? acc(c) : x_[std::size_t(v) * p_ + c];
      yn_[v] = cnt > 0 ? acc(p_) : yd_[v];
    }
    const std::size_t mo = xn_.size();
    std::copy(x_.begin(), x_.begin() + mo, x_old_.begin());
    std::copy(xn_.begin(), xn_.end(), x_.begin());
    std::copy(yn_.begin(), yn_.end(), yd_.begin());
    ++k_;
  }

  const std::vector<double>& positions() const override { return x_; }
  const double* previous_positions() const override { return x_old_.data(); }
  void change_norms(double* d, double* s) const override { detail::diff_norms(prob_, x_.data(), x_old_.data(), d, s); }

  // Collective: the ESDP objective sum_b <C_b, S_b> + const at the blocks of
  // the last iteration (before the first, at the lifting of x0), each sensor
  // edge once (from its smaller end); and the consensus residual
  // ||S_b - E_b(v)||_F over all blocks, both summed exactly.
  double objective() override {
    exchange();
    const auto& gr = prob_.graph();
    detail::ExactSum s[2];
    for (LocalId v = 0; v < prob_.num_owned(); ++v) {
      for (auto e = gr.offsets()[v]; e < gr.offsets()[v + 1]; ++e) {
        if (gr.global_id(gr.adjacency()[e]) < gr.global_id(v)) continue;
        const Mat g = edge_view(v, e), c = edge_cost(gr.edge_value(e));
        const Mat b = k_ > 0 ? stored(es_, e, p_ + 3) : g;
        s[0].add((c.cwiseProduct(b)).sum() + 0.5 * gr.edge_value(e) * gr.edge_value(e));
        s[1].add((b - g).squaredNorm());
      }
      for (auto t = prob_.anchor_offsets()[v]; t < prob_.anchor_offsets()[v + 1]; ++t) {
        const double* a = anchor(t);
        const double r = prob_.anchor_ranges()[t];
        const Mat g = anchor_view(v, t), c = anchor_cost(a, r);
        const Mat b = k_ > 0 ? stored(as_, t, p_ + 2) : g;
        double aa = 0;
        for (int q = 0; q < p_; ++q) aa += a[q] * a[q];
        s[0].add((c.cwiseProduct(b)).sum() + 0.5 * (r * r + aa));
        s[1].add((b - g).squaredNorm());
      }
    }
    detail::allreduce_exact(s, 2, prob_.comm());
    objective_ = s[0].value();
    residual_ = std::sqrt(s[1].value());
    return objective_;
  }
  void report(std::vector<std::pair<std::string, double>>* values,
              std::vector<std::pair<std::string, std::string>>*) const override {
    values->push_back({"relaxation_objective", objective_});
    values->push_back({"consensus_residual", residual_});
    values->push_back({"admm_rho", rho_});
  }
  std::int64_t memory_bytes() const override {
    std::size_t d = x_.capacity() + yd_.capacity() + x_old_.capacity() + xn_.capacity() + yn_.capacity();
    for (const auto* a : {&es_, &eu_, &ev_, &as_, &au_, &av_}) d += a->capacity();
    return static_cast<std::int64_t>(sizeof(double) * d);
  }
  void save(StateWriter& w) const override {
    const int qe = (p_ + 3) * (p_ + 3), qa = (p_ + 2) * (p_ + 2);
    w.scalar("k", double(k_));
    w.node_rows("x", x_.data(), p_);
    w.node_rows("x_old", x_old_.data(), p_);
    w.node_rows("Y", yd_.data(), 1);
    w.edge_rows("S", es_.data(), qe), w.edge_rows("U", eu_.data(), qe), w.edge_rows("V", ev_.data(), qe);
    w.anchor_rows("S_anchor", as_.data(), qa), w.anchor_rows("U_anchor", au_.data(), qa);
    w.anchor_rows("V_anchor", av_.data(), qa);
  }
  void load(const StateReader& r) override {
    const int qe = (p_ + 3) * (p_ + 3), qa = (p_ + 2) * (p_ + 2);
    k_ = static_cast<std::int64_t>(r.scalar("k"));
    r.node_rows("x", x_.data(), p_);
    r.node_rows("x_old", x_old_.data(), p_);
    r.node_rows("Y", yd_.data(), 1);
    r.edge_rows("S", es_.data(), qe), r.edge_rows("U", eu_.data(), qe), r.edge_rows("V", ev_.data(), qe);
    r.anchor_rows("S_anchor", as_.data(), qa), r.anchor_rows("U_anchor", au_.data(), qa);
    r.anchor_rows("V_anchor", av_.data(), qa);
  }

 private:
  Eigen::Map<const Eigen::VectorXd> row(const double* a, LocalId v) const {
    return Eigen::Map<const Eigen::VectorXd>(a + std::size_t(v) * p_, p_);
  }
  const double* anchor(std::int64_t t) const {
    return prob_.anchors().data() + std::size_t(prob_.anchor_ids()[t]) * p_;
  }
  static Mat stored(const std::vector<double>& a, std::int64_t e, int q) {
    return Eigen::Map<const Eigen::MatrixXd>(a.data() + std::size_t(e) * q * q, q, q);
  }
  static void store(std::vector<double>& a, std::int64_t e, const Mat& b) {
    const int q = static_cast<int>(b.rows());
    Eigen::Map<Eigen::MatrixXd>(a.data() + std::size_t(e) * q * q, q, q) = b;
  }
  void exchange() {
    prob_.graph().halo().exchange(x_.data(), p_);
    prob_.graph().halo().exchange(yd_.data(), 1);
  }

  // E_b(v) of a sensor edge (v, u): rows p and p+1 are the smaller and the
  // larger global id (both ends build the same matrix), row p+2 the border.
  Mat edge_view(LocalId v, std::int64_t e) const {
    const auto& gr = prob_.graph();
    const LocalId u = gr.adjacency()[e];
    const bool v_first = gr.global_id(v) < gr.global_id(u);
    const int q = p_ + 3, L = p_ + 2;
    Mat g = stored(ev_, e, q);  // the block's own entries: Y_ij and the border
    g.topLeftCorner(p_, p_).setIdentity();
    g(L, L) = 1.0;
    place_node(g, p_, v_first ? v : u);
    place_node(g, p_ + 1, v_first ? u : v);
    return g;
  }
  Mat anchor_view(LocalId v, std::int64_t t) const {
    const int q = p_ + 2, L = p_ + 1;
    Mat g = stored(av_, t, q);  // the border
    g.topLeftCorner(p_, p_).setIdentity();
    g(L, L) = 1.0;
    place_node(g, p_, v);
    return g;
  }
  // Row/column r of the block holds (x_w, Y_ww).
  void place_node(Mat& g, int r, LocalId w) const {
    for (int c = 0; c < p_; ++c) g(r, c) = g(c, r) = x_[std::size_t(w) * p_ + c];
    g(r, r) = yd_[w];
  }
  // <C, S> = (Y_ii + Y_jj - 2 Y_ij) / 2 - d (m_i - m_j), m the border column
  // (the lifted term (D - 2 d delta) / 2 with delta = m_i - m_j); a symmetric
  // off-diagonal entry counts twice in <C, S>.
  Mat edge_cost(double d) const {
    const int q = p_ + 3, i = p_, j = p_ + 1, L = p_ + 2;
    Mat c = Mat::Zero(q, q);
    c(i, i) = c(j, j) = 0.5;
    c(i, j) = c(j, i) = -0.5;
    c(i, L) = c(L, i) = -0.5 * d;
    c(j, L) = c(L, j) = 0.5 * d;
    return c;
  }
  // <C, S> = (Y_ii - 2 a'x_i) / 2 - r (m_i - a'm_x) (D = |a|^2 - 2 a'x_i + Y_ii,
  // delta = w'm with w = (-a, 1)); the constants go to objective().
  Mat anchor_cost(const double* a, double r) const {
    const int q = p_ + 2, i = p_, L = p_ + 1;
    Mat c = Mat::Zero(q, q);
    c(i, i) = 0.5;
    for (int k = 0; k < p_; ++k) {
      c(i, k) = c(k, i) = -0.5 * a[k];
      c(k, L) = c(L, k) = 0.5 * r * a[k];
    }
    c(i, L) = c(L, i) = -0.5 * r;
    return c;
  }

  // One ADMM step of block b with view g and cost c (state arrays s, u, own,
  // entry t); returns (x_w, Y_ww) of S_b + U_b at row r (w's contribution to
  // its average) and keeps the block's own entries of S_b + U_b.
  BlockVec block_step(const Mat& g, const Mat& c, std::vector<double>& s, std::vector<double>& u,
                      std::vector<double>& own, std::int64_t t, int r) {
    Mat ub = stored(u, t, static_cast<int>(g.rows()));
    if (k_ > 0) ub += stored(s, t, static_cast<int>(g.rows())) - g;
    const Mat sb = project_psd(g - ub - c / rho_);
    const Mat w = sb + ub;
    store(s, t, sb);
    store(u, t, ub);
    store(own, t, w);  // only the own entries are read back (edge_view/anchor_view overwrite the rest)
    BlockVec out(p_ + 1);
    for (int q = 0; q < p_; ++q) out(q) = w(r, q);
    out(p_) = w(r, r);
    return out;
  }
  BlockVec edge_step(LocalId v, std::int64_t e) {
    const auto& gr = prob_.graph();
    const int r = gr.global_id(v) < gr.global_id(gr.adjacency()[e]) ? p_ : p_ + 1;
    return block_step(edge_view(v, e), edge_cost(gr.edge_value(e)), es_, eu_, ev_, e, r);
  }
  BlockVec anchor_step(LocalId v, std::int64_t t) {
    return block_step(anchor_view(v, t), anchor_cost(anchor(t), prob_.anchor_ranges()[t]), as_, au_, av_, t, p_);
  }
  // Euclidean projection onto the PSD cone: the negative eigenvalues set to 0.
  Mat project_psd(const Mat& a) {
    eig_.compute(a);
    const BlockVec lam = eig_.eigenvalues().cwiseMax(0.0);
    return eig_.eigenvectors() * lam.asDiagonal() * eig_.eigenvectors().transpose();
  }

  LocalizationProblem& prob_;
  double rho_;
  int p_;
  std::vector<double> x_, yd_, x_old_, xn_, yn_;
  // Per sensor-edge entry (CSR order) and per anchor measurement: the block
  // S_b, its scaled dual U_b and the block's own consensus entries, q*q each.
  std::vector<double> es_, eu_, ev_, as_, au_, av_;
  Eigen::SelfAdjointEigenSolver<Mat> eig_{kMaxOrder};
  std::int64_t k_ = 0;
  double objective_ = NAN, residual_ = NAN;
};

}  // namespace

namespace detail {

std::unique_ptr<Algorithm> make_esdp_dist(LocalizationProblem& prob, const SolverOptions& opt) {
  return std::make_unique<EsdpDist>(prob, opt.esdp_rho);
}

}  // namespace detail

}  // namespace snl

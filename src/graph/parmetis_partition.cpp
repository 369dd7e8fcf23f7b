// ParMETIS_V3_PartKway through PT-Scotch's compatibility interface, over the
// block-distributed graph (built only with PT-Scotch's ParMETIS).
#ifdef SNL_HAVE_PARMETIS
#include <metis.h>
#define SCOTCH_METIS_RETURN  // METIS_OK etc. come from metis.h (the same values)
#include <parmetis.h>  // PT-Scotch's compatibility header: idx_t is SCOTCH_Num, real_t is float

#include <algorithm>

#include "graph/partition_detail.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/graph/dist_graph.hpp"
#include "snl/graph/partition.hpp"
#include "snl/io/network.hpp"

namespace snl::detail {

// ParMETIS's idx_t in PT-Scotch's header; the CMake module picks the 64-bit build.
using pidx_t = SCOTCH_Num;
static_assert(sizeof(pidx_t) == 8, "PT-Scotch's ParMETIS interface must be the 64-bit build (parmetis-int64)");

struct HalfEdge {
  GlobalId v, u;
};

// ParMETIS_V3_PartKway over the block-distributed graph: each edge goes to the
// block owners of both ends, which build their rows of the CSR. Collective;
// returns "" on success, else why it could not run. PT-Scotch's result may
// vary between runs (threads, message order): the iterates do not depend on it.
std::string parmetis_partition(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges,
                               std::vector<int>& block, PhaseMarks& phase, std::int64_t& peak) {
  const int size = comm_size(comm), rank = comm_rank(comm);
  GlobalId b, e;
  block_range(n, size, rank, b, e);
  std::vector<HalfEdge> mine;
  {
    std::vector<std::vector<HalfEdge>> out(size);
    for (std::size_t k = 0; k < edges.size(); k += 2) {
      out[block_owner(n, size, edges[k])].push_back({edges[k], edges[k + 1]});
      out[block_owner(n, size, edges[k + 1])].push_back({edges[k + 1], edges[k]});
    }
    mine = exchange_records(comm, out);
  }
  std::vector<pidx_t> vtxdist(size + 1), xadj(static_cast<std::size_t>(e - b) + 1, 0), adjncy(mine.size());
  for (int r = 0; r <= size; ++r) {
    GlobalId rb, re;
    block_range(n, size, std::min(r, size - 1), rb, re);
    vtxdist[r] = r == size ? re : rb;
  }
  for (const HalfEdge& h : mine) ++xadj[h.v - b + 1];
  for (std::size_t v = 0; v + 1 < xadj.size(); ++v) xadj[v + 1] += xadj[v];
  {
    std::vector<pidx_t> fill(xadj.begin(), xadj.end() - 1);
    for (const HalfEdge& h : mine) adjncy[fill[h.v - b]++] = h.u;
  }
  peak = static_cast<std::int64_t>(mine.capacity() * sizeof(HalfEdge) +
                                   (xadj.size() + adjncy.size() + vtxdist.size()) * sizeof(pidx_t));
  release(mine);
  phase("parmetis_graph");
  pidx_t wgtflag = 0, numflag = 0, ncon = 1, nparts = size, edgecut = 0;
  pidx_t options[3] = {0, 0, 0};
  std::vector<float> tpwgts(size, 1.0f / static_cast<float>(size));
  float ubvec = 1.03f;  // METIS's default imbalance tolerance (ufactor 30)
  std::vector<pidx_t> part(xadj.size() - 1, 0);
  MPI_Comm c = comm;
  int status = METIS_ERROR;
  try {
    status = ParMETIS_V3_PartKway(vtxdist.data(), xadj.data(), adjncy.data(), nullptr, nullptr, &wgtflag, &numflag,
                                  &ncon, &nparts, tpwgts.data(), &ubvec, options, &edgecut, part.data(), &c);
  } catch (...) {
    status = METIS_ERROR;
  }
  if (!all_ranks(comm, status == METIS_OK)) return "ParMETIS (PT-Scotch) failed";
  block.assign(part.begin(), part.end());
  phase("parmetis");
  return "";
}

}  // namespace snl::detail
#endif

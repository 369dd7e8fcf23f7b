"""snl.consensus: distributed consensus optimisation (seed 001) from Python.

min_x sum_p f_p(x) over a connected network where node p knows only f_p:
problems from arrays (your own samples per node, for logistic regression or
least squares), from files or from the generator, solved by `solve` with the
options of `snl consensus solve` as keywords; x is the CLI's, bit for bit
(docs/python.md, docs/consensus.md).
"""
import numpy as np

from . import _snl
from . import _array, _comm_handle

FAMILIES = ("exp", "quadratic", "logistic", "least_squares")


class Problem:
    """A consensus problem on n nodes with links `edges` ((E, 2) node ids).

    family "logistic" / "least_squares": `features` (S, q), `labels` (S,)
    (+-1 for logistic, real targets for least squares), `owner` (S,) the node
    of each sample, `lam` > 0: f_p(x) = sum over p's samples of the loss +
    (lam / 2n) x.x. "quadratic": `quad_h`, `quad_r` (n, q). "exp" (q = 1):
    `exp_a` .. `exp_d` (n,). `truth_path`: a Hamilton path (for newton-path).
    The file reader's checks apply: a bad problem raises ValueError with its
    message."""

    def __init__(self, edges, family, n_nodes=None, *, features=None, labels=None, owner=None, lam=1.0,
                 quad_h=None, quad_r=None, exp_a=None, exp_b=None, exp_c=None, exp_d=None, truth_path=None,
                 _raw=None):
        if _raw is not None:
            self._raw = _raw
            return
        if family not in FAMILIES:
            raise ValueError(f"family must be one of {', '.join(FAMILIES)}, got {family!r}")
        e = _array(edges, "edges", np.int64, 2, cols=2)
        arrays = {}
        if family in ("logistic", "least_squares"):
            if features is None or labels is None or owner is None:
                raise ValueError(f"family {family} needs features, labels and owner")
            a = _array(features, "features", np.float64, 2)
            arrays["features"] = a
            arrays["labels"] = _array(labels, "labels", np.float64, 1, rows=a.shape[0])
            arrays["owner"] = _array(owner, "owner", np.int64, 1, rows=a.shape[0])
            q = a.shape[1]
            if n_nodes is None:
                n_nodes = int(max(e.max(initial=-1), arrays["owner"].max(initial=-1))) + 1
        elif family == "quadratic":
            if quad_h is None or quad_r is None:
                raise ValueError("family quadratic needs quad_h and quad_r")
            h = _array(quad_h, "quad_h", np.float64, 2)
            arrays["quad_h"] = h
            arrays["quad_r"] = _array(quad_r, "quad_r", np.float64, 2, cols=h.shape[1], rows=h.shape[0])
            q = h.shape[1]
            n_nodes = h.shape[0] if n_nodes is None else n_nodes
        else:
            if any(v is None for v in (exp_a, exp_b, exp_c, exp_d)):
                raise ValueError("family exp needs exp_a, exp_b, exp_c and exp_d")
            for k, v in (("exp_a", exp_a), ("exp_b", exp_b), ("exp_c", exp_c), ("exp_d", exp_d)):
                arrays[k] = _array(v, k, np.float64, 1)
            q = 1
            n_nodes = arrays["exp_a"].shape[0] if n_nodes is None else n_nodes
        path = None if truth_path is None else _array(truth_path, "truth_path", np.int64, 1)
        self._raw = _snl.consensus_from_arrays(family, int(n_nodes), int(q), e, path, arrays, float(lam))

    @classmethod
    def from_file(cls, path, comm=None):
        """Reads an snl-consensus problem file (collective over comm)."""
        return cls(None, None, _raw=_snl.consensus_read(str(path), _comm_handle(comm)))

    def save(self, path, comm=None):
        """Writes the problem file atomically (collective over comm)."""
        self._raw.save(str(path), _comm_handle(comm))

    n_nodes = property(lambda self: self._raw.n_nodes)
    dim = property(lambda self: self._raw.dim)
    family = property(lambda self: self._raw.family)
    lam = property(lambda self: self._raw.lam)
    edges = property(lambda self: self._raw.edges)
    truth_path = property(lambda self: self._raw.truth_path)
    features = property(lambda self: self._raw.features)
    labels = property(lambda self: self._raw.labels)
    owner = property(lambda self: self._raw.owner)
    quad_h = property(lambda self: self._raw.quad_h)
    quad_r = property(lambda self: self._raw.quad_r)

    def __repr__(self):
        return f"snl.consensus.Problem({self.family}: n={self.n_nodes}, q={self.dim})"


def generate(nodes, family="exp", dim=1, avg_degree=6.0, hamiltonian=False, seed=1, samples_per_node=20, lam=1.0):
    """`snl consensus generate`'s problem (the same bits for the same options)."""
    return Problem(None, None, _raw=_snl.consensus_generate(int(nodes), str(family), int(dim), float(avg_degree),
                                                            bool(hamiltonian), int(seed), int(samples_per_node),
                                                            float(lam)))


class Result:
    """x: (n, q) every node's copy, on every rank; summary: dict (method, dual,
    termination, iterations, dual_iterations, max_abs_error, F, messages, x_star,
    ...); history: dict of numpy arrays, one entry per primal iteration."""

    def __init__(self, d):
        self.x = d["x"]
        self.summary = d["summary"]
        self.history = d["history"]

    def __repr__(self):
        s = self.summary
        return f"snl.consensus.Result({s['method']}: {s['termination']} after {s['iterations']} iterations)"


def solve(problem, method="newton-tree", comm=None, progress=None, **options):
    """`snl consensus solve` on `problem` (collective; None on ranks other than
    0 when rank 0 holds the problem). Keywords: dual, max_iter, dual_max_iter,
    tol, oracle_tol, dual_tol, step ("armijo", "damped", or alpha0 for the
    baselines), damping, partition. progress: called on rank 0 with a dict per
    primal iteration. Ctrl-C raises KeyboardInterrupt on every rank."""
    if problem is not None and not isinstance(problem, Problem):
        raise TypeError(f"expected an snl.consensus.Problem (or None on ranks other than 0), got "
                        f"{type(problem).__name__}")
    options["method"] = method
    raw = None if problem is None else problem._raw
    return Result(_snl.consensus_solve(raw, options, _comm_handle(comm), progress))

"""snl: sensor network localization from Python (docs/python.md).

A thin layer over libsnl: the arrays are shaped here, every computation is the
library's (the same calls as the `snl` command line, so positions are
bit-identical to `snl solve`). Serial, or under `mpirun -np K python3 script.py`.
"""
import ctypes
import ctypes.util
import atexit

import numpy as np

# Open MPI's plugins resolve symbols of libmpi: load it globally before the
# extension (mpi4py does the same).
_libmpi = ctypes.util.find_library("mpi")
if _libmpi:
    try:
        ctypes.CDLL(_libmpi, mode=ctypes.RTLD_GLOBAL)
    except OSError:
        pass

from . import _snl  # noqa: E402

Error = _snl.Error  # a ValueError: every invalid input or option
NumericalFailure = _snl.NumericalFailure

if _snl.init_mpi():  # MPI was not initialized (no mpi4py yet): ours to finalize
    atexit.register(_snl.finalize_mpi)

#: The algorithm `snl solve` runs without --algorithm (the library's default).
DEFAULT_ALGORITHM = _snl.default_algorithm()


def algorithms():
    """Every --algorithm name of the registry."""
    return list(_snl.algorithms())


def _comm_handle(comm):
    """An mpi4py communicator's handle (an int), or None for MPI_COMM_WORLD."""
    if comm is None:
        return None
    if isinstance(comm, int):
        return comm
    handle = getattr(comm, "handle", None)  # mpi4py >= 4
    if isinstance(handle, int):
        return handle
    from mpi4py import MPI
    return MPI._handleof(comm)


def rank(comm=None):
    return _snl.comm_rank(_comm_handle(comm))


def size(comm=None):
    return _snl.comm_size(_comm_handle(comm))


def _array(a, name, dtype, ndim, cols=None, rows=None):
    """`a` as a C-contiguous array of dtype, with a clear ValueError on a bad shape or type."""
    try:
        arr = np.asarray(a)
    except Exception as e:  # ragged lists and the like
        raise ValueError(f"{name}: not an array ({e})") from None
    if dtype is np.int64:
        if arr.size == 0:
            arr = arr.astype(np.int64)
        if arr.dtype.kind not in "iu":
            raise ValueError(f"{name} must be an integer array, got dtype {arr.dtype}")
    elif arr.dtype.kind not in "iuf":
        raise ValueError(f"{name} must be a real array, got dtype {arr.dtype}")
    if arr.size == 0 and ndim == 2 and cols is not None:
        arr = arr.reshape(0, cols)
    if arr.ndim != ndim:
        raise ValueError(f"{name} must have {ndim} dimension(s), got shape {arr.shape}")
    if cols is not None and arr.shape[1] != cols:
        raise ValueError(f"{name} must have {cols} columns, got shape {arr.shape}")
    if rows is not None and arr.shape[0] != rows:
        raise ValueError(f"{name} must have {rows} rows, got shape {arr.shape}")
    return np.ascontiguousarray(arr, dtype=dtype)


class Network:
    """A whole network: anchors, range measurements, optionally truth and sigmas.

    edges: (E, 2) ints over sensors and anchors: ids 0..n-1 are the sensors,
    n..n+m-1 the anchors (anchor k is n + k); a row joins a sensor to a sensor
    or to an anchor. ranges: (E,). sigmas: None, one float (the network's
    noise standard deviation) or (E,) per-measurement standard deviations.
    Rows keep their order in the file's sensor_edges and anchor_edges, so a
    network built from a file's arrays is that file's network.
    """

    def __init__(self, anchors, n_sensors, edges, ranges, sigmas=None, dim=2, truth=None):
        dim = int(dim)
        if dim not in (1, 2, 3):
            raise ValueError(f"dim must be 1, 2 or 3, got {dim}")
        n = int(n_sensors)
        if n != n_sensors:
            raise ValueError(f"n_sensors must be an integer, got {n_sensors}")
        if n < 1:
            raise ValueError(f"n_sensors must be >= 1, got {n}")
        A = _array(anchors, "anchors", np.float64, 2, cols=dim)
        m = A.shape[0]
        E = _array(edges, "edges", np.int64, 2, cols=2)
        r = _array(ranges, "ranges", np.float64, 1, rows=E.shape[0])
        if E.size and (E.min() < 0 or E.max() >= n + m):
            row = int(np.flatnonzero((E < 0).any(1) | (E >= n + m).any(1))[0])
            raise ValueError(f"edges row {row}: node id out of range [0, {n + m}) "
                             f"(sensors 0..{n - 1}, anchors {n}..{n + m - 1})")
        is_anchor = E >= n
        both = is_anchor.all(1)
        if both.any():
            row = int(np.flatnonzero(both)[0])
            raise ValueError(f"edges row {row}: ({E[row, 0]}, {E[row, 1]}) joins two anchors")
        to_anchor = is_anchor.any(1)
        s_rows = ~to_anchor
        se = E[s_rows]
        ae = E[to_anchor]
        # (sensor, anchor k) whichever order the row has.
        swap = ae[:, 0] >= n
        ae = np.where(swap[:, None], ae[:, ::-1], ae)
        ae = np.ascontiguousarray(np.stack([ae[:, 0], ae[:, 1] - n], axis=1) if ae.size else ae.reshape(0, 2))
        sigma = None
        s_sig = a_sig = None
        if sigmas is not None:
            if np.ndim(sigmas) == 0:
                sigma = float(sigmas)
                if not np.isfinite(sigma) or sigma < 0:
                    raise ValueError(f"sigma must be finite and >= 0, got {sigma}")
            else:
                sg = _array(sigmas, "sigmas", np.float64, 1, rows=E.shape[0])
                s_sig, a_sig = sg[s_rows], sg[to_anchor]
        T = None if truth is None else _array(truth, "truth", np.float64, 2, cols=dim, rows=n)
        self._net = _snl.from_arrays(dim, n, A, se, r[s_rows], ae, r[to_anchor], T, sigma, s_sig, a_sig)

    @classmethod
    def _wrap(cls, net):
        self = cls.__new__(cls)
        self._net = net
        return self

    @classmethod
    def from_file(cls, path, **csv):
        """An HDF5 network file (docs/formats.md), or with .csv/.txt the
        sensor-edge table of `snl import` plus anchor_edges=, anchors=,
        truth=, n_sensors=, index_base=, sigma= (the other tables)."""
        path = str(path)
        if path.endswith((".csv", ".txt")) or csv:
            return cls.from_csv(path, **csv)
        return cls._wrap(_snl.read_network(path))

    @classmethod
    def from_csv(cls, sensor_edges, anchor_edges, anchors, truth=None, n_sensors=0, index_base=0, sigma=None):
        """The text tables of `snl import` (docs/formats.md, "Text files")."""
        return cls._wrap(_snl.from_csv(str(sensor_edges), str(anchor_edges), str(anchors),
                                       "" if truth is None else str(truth), int(n_sensors), int(index_base),
                                       -1.0 if sigma is None else float(sigma)))

    def save(self, path, comm=None):
        """Writes the network file (HDF5); collective over comm, rank 0 writes."""
        self._net.save(str(path), _comm_handle(comm))

    dim = property(lambda self: self._net.dim)
    n_sensors = property(lambda self: self._net.n_sensors)
    n_anchors = property(lambda self: self._net.n_anchors)
    anchors = property(lambda self: self._net.anchors)
    truth = property(lambda self: self._net.truth)
    sigma = property(lambda self: self._net.sigma)
    sensor_edges = property(lambda self: self._net.sensor_edges)
    sensor_ranges = property(lambda self: self._net.sensor_ranges)
    anchor_edges = property(lambda self: self._net.anchor_edges)
    anchor_ranges = property(lambda self: self._net.anchor_ranges)

    @property
    def edges(self):
        """(E, 2) in the constructor's convention: sensor edges, then anchor edges (anchor k as n + k)."""
        ae = self._net.anchor_edges.copy()
        ae[:, 1] += self.n_sensors
        return np.concatenate([self._net.sensor_edges, ae])

    @property
    def ranges(self):
        return np.concatenate([self._net.sensor_ranges, self._net.anchor_ranges])

    def __repr__(self):
        return (f"snl.Network(n_sensors={self.n_sensors}, n_anchors={self.n_anchors}, dim={self.dim}, "
                f"sensor_edges={len(self.sensor_ranges)}, anchor_edges={len(self.anchor_ranges)})")


def generate(n_sensors=None, **options):
    """A random geometric network, as `snl generate` (keywords: its options,
    dashes as underscores: dim, avg_degree, sigma, sigma_rel, side, anchors,
    anchor_radius, seed, localizable, max_draws, topology, noise, ...)."""
    if n_sensors is not None:
        options["sensors"] = n_sensors
    return Network._wrap(_snl.generate(options))


class Result:
    """positions: (n, dim) in sensor order; summary: dict (termination,
    iterations, costs, gap certificate, messages, bytes, times); history: dict
    of numpy arrays, one entry per recorded iteration."""

    def __init__(self, d):
        self.positions = d["positions"]
        self.summary = d["summary"]
        self.history = d["history"]

    def __repr__(self):
        s = self.summary
        return f"snl.Result({s['algorithm']}: {s['termination']} after {s['iterations']} iterations)"


def _raw(net):
    """The library's network of `net` (None: given on another rank)."""
    if net is None:
        return None
    if not isinstance(net, Network):
        raise TypeError(f"expected an snl.Network (or None on ranks other than 0), got {type(net).__name__}")
    return net._net


def _start(init):
    """(kind, rows) for the library: auto | random | dv, or positions in sensor order."""
    if init is None:
        return "auto", None
    if isinstance(init, str):
        if init not in ("auto", "random", "dv"):
            raise ValueError(f"init must be 'auto', 'random', 'dv', positions or a Result, not '{init}'")
        return init, None
    if isinstance(init, Result):
        init = init.positions
    x = _array(init, "init", np.float64, 2)
    return "positions", x


def solve(net, algorithm=None, init=None, comm=None, progress=None, callback=None, **options):
    """Localizes the sensors of `net`, as `snl solve` (docs/python.md).

    algorithm: a registry name (default: DEFAULT_ALGORITHM, as the CLI).
    init: None/'auto', 'random', 'dv', an (n, dim) array or a Result (warm start).
    options: every `snl solve` option as a keyword (max_iter, tol, stop, ...),
    checked by the same registry: one the algorithm cannot honour raises.
    progress(record): called on rank 0 at every recorded iteration.
    callback(record): called on every rank; a true return value stops the run.
    Under MPI: collective; net given on rank 0 (None elsewhere) or on every rank.
    """
    kind, rows = _start(init)
    alg = DEFAULT_ALGORITHM if algorithm is None else str(algorithm)
    raw = _raw(net)
    return Result(_snl.solve(raw, alg, kind, rows, _comm_handle(comm), progress, callback, options))


def track(frames, algorithm=None, init=None, comm=None, warm_algorithm=None, warm_tol=None, **options):
    """Solves a sequence of networks (same sensors, moving), each frame
    warm-started from the last frame's positions; the first frame from `init`
    with `algorithm`, the others with `warm_algorithm` (None: `algorithm`;
    "ml-agd" converges fastest from a nearby start) and, if given, `--tol
    warm_tol` (1e-3 keeps the RMSE and saves most iterations, docs/python.md).
    Returns the list of Results."""
    results = []
    start = init
    for net in frames:
        alg = algorithm if not results or warm_algorithm is None else warm_algorithm
        opts = options if not results or warm_tol is None else dict(options, tol=warm_tol)
        r = solve(net, algorithm=alg, init=start, comm=comm, **opts)
        results.append(r)
        start = r.positions
    return results


def evaluate(net, result, comm=None, weights="auto", loss="l2"):
    """Costs and errors of positions (a Result or an (n, dim) array), as `snl eval`:
    rmse, mpe (NaN without truth), their localizable twins, the ML and relaxed
    costs, and `localizable` (a boolean mask of the sensors that can be localized)."""
    x = result.positions if isinstance(result, Result) else result
    x = _array(x, "positions", np.float64, 2)
    raw = _raw(net)
    return _snl.evaluate(raw, x, str(weights), str(loss), _comm_handle(comm))


def crlb(net, sigma=None, at=None):
    """Cramer-Rao lower bound, as `snl eval --crlb`: per-sensor covariances,
    (n, dim, dim); NaN for sensors outside the anchored rigid part. sigma:
    one noise standard deviation (default: the network's); at: positions
    (default: the truth)."""
    if sigma is not None and not float(sigma) >= 0:
        raise ValueError(f"sigma must be >= 0, got {sigma}")
    x = None
    if at is not None:
        x = _array(at.positions if isinstance(at, Result) else at, "at", np.float64, 2)
    if net is None:
        raise TypeError("crlb runs on the calling process: give it the network there")
    d = _snl.crlb(_raw(net), -1.0 if sigma is None else float(sigma), x)
    cov = d["covariance"]
    cov[np.asarray(d["outside"], dtype=np.int64)] = np.nan
    return cov


from . import consensus  # noqa: E402,F401  (snl.consensus: seed 001 from Python)

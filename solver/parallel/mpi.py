"""K processes over MPI: the grid cut into slabs, one per process (Karamelo 3.5).

Each process holds the particles of its slab and a local grid covering the node
layers they touch (its halo: owned nodes plus ghost nodes owned by neighbours).
In a step:

    sum_ghosts   after each particle-to-grid transfer, every process sends what
                 it added to ghost nodes to their owners, which add it up (in
                 rank order, so the sum is deterministic);
    share_nodes  after the grid update, owners send the nodal values back to
                 the processes holding them as ghosts;
    migrate      after G2P, particles that crossed into another slab move to
                 its process with every per-particle array (Particles.arrays());
                 every `rebalance_every` steps the cuts move so that each slab
                 holds about the same number of particles (MPM3DMP 4.3), or, with
                 `balance: "work"`, the same work: each process's time since the
                 last rebalancing, less what it spent communicating and waiting
                 for the others, shared out evenly over the particles it held.

Total-Lagrangian scenes (formulation tlmpm) own particles by their reference
position X: the grid is the reference configuration and X never changes, so
the slabs are balanced once, at the start, and particles never migrate.

Reductions (energies, the time step, checks), failures and the stop decision
are collective, so every process takes the same branch at the same step.
"""
from __future__ import annotations

import functools
from time import perf_counter
from types import SimpleNamespace

import numpy as np
from mpi4py import MPI

from solver import shape
from solver.boundary import Constraints
from solver.parallel.binning import bin_particles, owners
from solver.parallel.single import PARTICLES_MOVED, SLABS_MOVED, UNCHANGED
from solver.parallel.slabs import balanced_cuts, even_cuts, layers_of, local_nodes, overlap, owned_nodes, split_axis
from solver.results import ResultWriter
from solver.state import Grid, grid_geometry, material_of_body, nodal_arrays

HALO_TAG = 17


def _waits(method):
    """The time in `method` is communication and waiting for the other processes, not this
    process's work (balance "work" leaves it out)."""
    @functools.wraps(method)
    def timed(self, *args, **kwargs):
        start = perf_counter()
        try:
            return method(self, *args, **kwargs)
        finally:
            self._waited += perf_counter() - start
    return timed


class SlabDomain:
    def __init__(self, comm: MPI.Comm, scene, support: int):
        self.comm = comm
        self.rank, self.processes = comm.rank, comm.size
        self.is_root = self.rank == 0
        self.support = support
        self.dimension = scene.dimension
        self.cells = np.asarray(scene.grid_shape(), dtype=np.int64)
        self.lower = np.asarray(scene.grid_lower(), dtype=np.float64)   # as make_grid places it
        self.h = np.asarray(scene.cell_sizes(), dtype=np.float64)
        self.axis = split_axis(self.cells)
        self._inv_h = 1.0 / self.h   # as Grid computes it
        self._whole_strides = _strides(self.cells + 1)
        self.rebalance_every = scene.parallel.rebalance_every
        self._by_work = scene.parallel.balance == "work"
        self._since: float | None = None   # when this process's work began to be measured
        self._waited = 0.0                  # time spent communicating since then
        self._by_reference = scene.method.formulation == "tlmpm"   # slabs of the reference configuration
        self.cuts = even_cuts(int(self.cells[self.axis]), self.processes)
        self._material = material_of_body(scene)
        self._failure: Exception | None = None
        self.halo_bytes = 0   # sent by sum_ghosts and share_nodes so far (benchmarks/scaling.py)
        self._plan()

    # -- slabs --------------------------------------------------------------------

    def _plan(self) -> None:
        """Local grid box and exchange lists of the current cuts."""
        k, me, s = self.processes, self.rank, self.support
        self.local = local_nodes(self.cuts, me, s)
        mine = owned_nodes(self.cuts, me)
        shift = self.local[0]
        # (peer, lo, hi) in local layers: my ghost layers that `peer` owns ...
        self._ghosts = [(q, lo - shift, hi - shift) for q in range(k) if q != me
                        for lo, hi in [overlap(self.local, owned_nodes(self.cuts, q)) or (0, 0)] if hi > lo]
        # ... and my owned layers that `peer` holds as ghosts.
        self._lent = [(r, lo - shift, hi - shift) for r in range(k) if r != me
                      for lo, hi in [overlap(mine, local_nodes(self.cuts, r, s)) or (0, 0)] if hi > lo]
        counts = self.cells + 1
        counts[self.axis] = self.local[1] - self.local[0]
        self._node_shape = tuple(int(c) for c in counts[::-1])   # nodes are numbered x fastest
        self._axis_position = self.dimension - 1 - self.axis
        self._node_offset = shift * int(np.prod(counts[:self.axis]))   # local stride of the split axis
        self._local_strides = _strides(counts)

    def grid(self, scene) -> Grid:
        lower = self.lower.copy()
        lower[self.axis] += self.local[0] * self.h[self.axis]
        cells = self.cells.copy()
        cells[self.axis] = self.local[1] - self.local[0] - 1
        fields = scene.grid_fields()   # contact: a velocity field per body, one after the other
        n = fields * int(np.prod(cells + 1))
        return Grid(lower=lower, h=self.h.copy(), cells=cells, fields=fields, **nodal_arrays(scene, n))

    def constraints(self, scene, grid: Grid) -> "_OwnedConstraints":
        return self.owned(Constraints(scene, grid_geometry(scene)), grid)

    def owned(self, whole, grid: Grid) -> "_OwnedConstraints":
        """Nodal conditions of the whole grid (node, axis, value, set_time) on the nodes this
        process owns, in local numbers."""
        numbering = SimpleNamespace(node_counts=self.cells + 1, strides=self._whole_strides)
        return _OwnedConstraints(whole, numbering, owned_nodes(self.cuts, self.rank), self.local[0], self.axis,
                                 grid.strides)

    def weights(self, module, spec, x, particles, grid: Grid, stencil) -> int:
        """Shape functions at the particles, numbered on the local grid.

        They are evaluated in the coordinates of the whole grid, bit for bit as one
        process does (a position relative to a shifted origin differs by round-off,
        and linear MPM turns round-off at a cell face into an O(1) difference of
        the velocity gradient). With the local strides the node numbers come out
        shifted by a constant along the split axis, which is taken off.
        """
        whole = SimpleNamespace(lower=self.lower, inv_h=self._inv_h, cells=self.cells, strides=grid.strides)
        outside = shape.evaluate(module, spec, x, particles, whole, stencil)
        stencil.idx -= self._node_offset
        return outside

    def frame(self, grid: Grid):
        """The fused kernels' frame: whole-grid coordinates (as `weights`), local node numbers."""
        return SimpleNamespace(lower=self.lower, h=self.h, inv_h=self._inv_h, cells=self.cells,
                               strides=grid.strides, offset=self._node_offset)

    # -- particles ----------------------------------------------------------------

    def distribute(self, particles) -> None:
        """Every process seeded every particle: keep those of this slab (cuts balanced first)."""
        if self.rebalance_every > 0:
            self.cuts = balanced_cuts(self._layer_counts(particles, local=False), self.processes)
            self._plan()
        dest = np.empty(particles.count, dtype=np.int64)
        self._owners(particles, dest)
        particles.take(np.flatnonzero(dest == self.rank))

    def migrate(self, particles, step: int) -> int:
        """Send the particles that left this slab to their owners; rebalance the slabs when due."""
        moved = UNCHANGED
        if self._by_reference:   # X never changes: nor do the owners
            return moved
        if self._since is None:   # from the end of the first step, which compiled the kernels
            self._since, self._waited = perf_counter(), 0.0
        if self.rebalance_every > 0 and step % self.rebalance_every == 0:
            cuts = self._rebalanced_cuts(particles)
            if not np.array_equal(cuts, self.cuts):
                self.cuts = cuts
                self._plan()
                moved = SLABS_MOVED
        dest = np.empty(particles.count, dtype=np.int64)
        leaving = self._owners(particles, dest)
        if self._total(leaving) == 0:
            return moved
        _, counts, order, start = bin_particles(dest, self.processes, 1)
        arrays = particles.arrays()
        # (np.take, not a[index]: numpy's fancy indexing copies (n, 3, 3) rows 4-5x slower)
        outgoing = [{name: np.take(a, order[start[r]:start[r + 1]], axis=0) for name, a in arrays.items()}
                    if r != self.rank and counts[r] else None for r in range(self.processes)]
        incoming = [part for part in self._all_to_all(outgoing) if part]
        stay = order[start[self.rank]:start[self.rank + 1]]
        particles.replace(_merged(arrays, stay, incoming, self._material), rearranged=True)
        return max(moved, PARTICLES_MOVED)

    def _rebalanced_cuts(self, particles) -> np.ndarray:
        """Cuts that even out the particles per slab, or (balance "work") their measured work:
        each layer weighs its particles times the time per particle of the process holding it."""
        if not self._by_work:
            return balanced_cuts(self._layer_counts(particles, local=True), self.processes)
        now = perf_counter()
        busy = max(now - self._since - self._waited, 0.0)
        load = self._layer_counts(particles, local=False) * (busy / max(particles.count, 1))
        whole = self._summed_on_root(load)
        cuts = balanced_cuts(whole, self.processes) if self.is_root else np.empty(self.processes + 1, np.int64)
        self._broadcast(cuts)   # (rank 0's: a floating sum may round differently on each process)
        self._since, self._waited = perf_counter(), 0.0
        return cuts

    @_waits
    def _total(self, count: int) -> int:
        return int(self.comm.allreduce(count))

    @_waits
    def _all_to_all(self, outgoing: list) -> list:
        return self.comm.alltoall(outgoing)

    @_waits
    def _summed_on_root(self, values: np.ndarray) -> np.ndarray:
        out = np.zeros_like(values)
        self.comm.Reduce(values, out, op=MPI.SUM, root=0)
        return out

    @_waits
    def _broadcast(self, values: np.ndarray) -> None:
        self.comm.Bcast(values, root=0)

    def _positions(self, particles) -> np.ndarray:
        """The positions that decide a particle's slab: X in TLMPM, x otherwise."""
        return particles.X if self._by_reference else particles.x

    def _owners(self, particles, dest: np.ndarray) -> int:
        a = self.axis
        x = self._positions(particles)
        return owners(x[:, a], float(self.lower[a]), float(1.0 / self.h[a]), self.cuts, self.rank, dest)

    def _layer_counts(self, particles, local: bool) -> np.ndarray:
        """Particles per cell layer along the split axis (summed over processes when `local`)."""
        a = self.axis
        x = self._positions(particles)
        finite = x[np.isfinite(x[:, a]), a]
        counts = np.bincount(layers_of(finite, self.lower[a], self.h[a], int(self.cells[a])),
                             minlength=int(self.cells[a])).astype(np.int64)
        if local:
            self.comm.Allreduce(MPI.IN_PLACE, counts, op=MPI.SUM)
        return counts

    # -- grid exchange ------------------------------------------------------------

    def _layers(self, array: np.ndarray, lo: int, hi: int) -> np.ndarray:
        """Layers lo:hi of the split axis, in every velocity field the array holds."""
        fields = array.shape[0] // int(np.prod(self._node_shape))
        shaped = array.reshape((fields,) + self._node_shape + array.shape[1:])
        return shaped[(slice(None),) * (self._axis_position + 1) + (slice(lo, hi),)]

    def owned_mask(self, grid: Grid) -> np.ndarray:
        """Which nodes of the local grid (of one field) this process owns."""
        lo, hi = owned_nodes(self.cuts, self.rank)
        layer = self.local[0] + (np.arange(grid.n_nodes) // self._local_strides[self.axis]) % grid.node_counts[self.axis]
        return (layer >= lo) & (layer < hi)

    def first_node(self, axis: int) -> int:
        """Whole-grid index, along `axis`, of the local grid's first node layer."""
        return int(self.local[0]) if axis == self.axis else 0

    def owned_local(self, nodes: np.ndarray) -> np.ndarray:
        """Whole-grid node numbers -> local node numbers of those this process owns, -1 for the others."""
        counts = self.cells + 1
        coords = (nodes[:, None] // self._whole_strides[None, :]) % counts[None, :]
        lo, hi = owned_nodes(self.cuts, self.rank)
        mine = (coords[:, self.axis] >= lo) & (coords[:, self.axis] < hi)
        coords[:, self.axis] -= self.local[0]
        return np.where(mine, coords @ self._local_strides, -1)

    def sum_ghosts(self, *node_arrays: np.ndarray) -> None:
        """Add what this process put on ghost nodes into their owners' values."""
        self._exchange(self._ghosts, self._lent, node_arrays, np.add)

    def share_nodes(self, *node_arrays: np.ndarray) -> None:
        """Copy the owners' nodal values onto the ghost nodes of the other processes."""
        self._exchange(self._lent, self._ghosts, node_arrays, lambda held, got, out: np.copyto(out, got))

    @_waits
    def _exchange(self, send, receive, node_arrays, combine) -> None:
        """Send the layers of `send` to their peers; combine what comes for `receive` into
        the local values, peer by peer in rank order (so sums are the same every run)."""
        sent = [np.concatenate([self._layers(a, lo, hi).ravel() for a in node_arrays]) for _, lo, hi in send]
        requests = [self.comm.Isend(buf, dest=peer, tag=HALO_TAG) for (peer, _, _), buf in zip(send, sent)]
        self.halo_bytes += sum(buf.nbytes for buf in sent)
        for peer, lo, hi in receive:
            views = [self._layers(a, lo, hi) for a in node_arrays]
            buf = np.empty(sum(v.size for v in views))
            self.comm.Recv(buf, source=peer, tag=HALO_TAG)
            at = 0
            for v in views:
                combine(v, buf[at:at + v.size].reshape(v.shape), out=v)
                at += v.size
        MPI.Request.Waitall(requests)

    # -- collective decisions -----------------------------------------------------

    def fail(self, error: Exception) -> None:
        """Remember the first failure; the step goes on so that no process waits forever."""
        if self._failure is None:
            self._failure = error

    @_waits
    def stop_if_failed(self) -> None:
        """Raise, on every process, the failure of the lowest rank that had one."""
        if self.comm.allreduce(self._failure is not None, op=MPI.LOR):
            failures = self.comm.allgather(self._failure)
            raise next(f for f in failures if f is not None)

    def sum(self, value):
        return self._reduce(value, MPI.SUM)

    def max(self, value):
        return self._reduce(value, MPI.MAX)

    def min(self, value):
        return self._reduce(value, MPI.MIN)

    @_waits
    def _reduce(self, value, op):
        a = np.array(value, dtype=np.float64)
        self.comm.Allreduce(MPI.IN_PLACE, a, op=op)
        return a if a.ndim else float(a)

    @_waits
    def any(self, flag: bool) -> bool:
        return bool(self.comm.allreduce(bool(flag), op=MPI.LOR))

    @_waits
    def barrier(self) -> None:
        self.comm.Barrier()

    @_waits
    def allgather(self, array: np.ndarray) -> np.ndarray:
        """The arrays of every process, concatenated in rank order, on every process."""
        return np.concatenate(self.comm.allgather(array))

    @_waits
    def root_says(self, flag: bool) -> bool:
        """Rank 0's answer on every process (for decisions taken on its clock)."""
        return bool(self.comm.bcast(bool(flag), root=0))

    # -- output -------------------------------------------------------------------

    def gather(self, fields) -> dict[str, np.ndarray] | None:
        """The fields of all particles (a mapping: solver/fields.py FrameFields forms them as they
        are read, here all at once), sorted by id, on rank 0 (None elsewhere)."""
        parts = self.comm.gather(dict(fields), root=0)
        if not self.is_root:
            return None
        merged = {name: np.concatenate([p[name] for p in parts]) for name in fields}
        order = np.argsort(merged["id"], kind="stable")
        return {name: np.ascontiguousarray(a[order]) for name, a in merged.items()}

    def writer(self, out_dir, scene, version: str):
        return ResultWriter(out_dir, scene, version) if self.is_root else _NoWriter()


def _strides(counts: np.ndarray) -> np.ndarray:
    """Node number strides of a grid with `counts` nodes per axis (x fastest, as Grid numbers them)."""
    return np.concatenate(([1], np.cumprod(counts)[:-1])).astype(np.int64)


def _merged(arrays: dict, stay: np.ndarray, incoming: list[dict], material: np.ndarray) -> dict:
    """The particles `stay` (rows of `arrays`) and the `incoming` blocks, sorted by material (the
    models' slices), then by id, as one process has them: each array taken into the new order by
    one np.take (from itself; with arrivals, from itself and the received blocks concatenated)."""
    n = next(iter(arrays.values())).shape[0]
    ids = np.concatenate([arrays["id"][stay]] + [part["id"] for part in incoming])
    bodies = np.concatenate([arrays["body"][stay]] + [part["body"] for part in incoming])
    arrived = n + np.arange(ids.size - stay.size)                  # rows behind the n of `arrays`
    source = np.concatenate([stay, arrived])[np.lexsort((ids, material[bodies]))]
    names = list(arrays) + list(dict.fromkeys(name for part in incoming for name in part if name not in arrays))
    merged = {}
    for name in names:   # (a state a model allocated on the sending side only: zeros here)
        like = arrays[name] if name in arrays else next(part[name] for part in incoming if name in part)
        mine = arrays[name] if name in arrays else np.zeros((n, *like.shape[1:]), dtype=like.dtype)
        block = np.concatenate([mine] + [_column(part, name, like) for part in incoming]) if incoming else mine
        merged[name] = np.take(block, source, axis=0)
    return merged


def _column(part: dict, name: str, like: np.ndarray) -> np.ndarray:
    """`name` of a received block, zeros when the sender never allocated it."""
    if name in part:
        return part[name]
    count = next(iter(part.values())).shape[0]
    return np.zeros((count, *like.shape[1:]), dtype=like.dtype)


class _OwnedConstraints:
    """The scene's constraints on the nodes this process owns, in local node numbers.

    Only owners impose them (and count their work); ghost copies get the imposed
    values through share_nodes.
    """

    def __init__(self, whole: Constraints, grid: Grid, owned: tuple[int, int], shift: int, axis: int,
                 local_strides: np.ndarray):
        def owned_local(nodes):
            coords = (nodes[:, None] // grid.strides[None, :]) % grid.node_counts[None, :]
            keep = (coords[:, axis] >= owned[0]) & (coords[:, axis] < owned[1])
            coords = coords[keep]
            coords[:, axis] -= shift
            return np.ascontiguousarray(coords @ local_strides, dtype=np.int64), keep

        self.node, keep = owned_local(whole.node)
        self._whole, self._keep = whole, keep
        self.axis = np.ascontiguousarray(whole.axis[keep])
        self.value = np.ascontiguousarray(whole.value[keep])
        self.time_dependent = whole.time_dependent
        if not isinstance(whole, Constraints):   # other nodal values (held temperatures, solver/thermal.py)
            return
        self.condition = whole.condition[keep]
        friction_node, kept = owned_local(whole.friction_node)
        self.friction_node = friction_node
        self.friction_axis, self.friction_sign, self.friction_mu = (
            np.ascontiguousarray(a[kept]) for a in (whole.friction_axis, whole.friction_sign, whole.friction_mu))

    def set_time(self, t: float) -> None:
        if self.time_dependent:
            self._whole.set_time(t)
            self.value[:] = self._whole.value[self._keep]


class _NoWriter:
    """Processes other than rank 0 write nothing."""

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        pass

    frame_count = 0
    series_count = 0

    def write_frame(self, step, time, fields) -> None:
        pass

    def copy_frames(self, source, count: int) -> None:
        pass

    def series(self) -> dict:
        return {}

    def append_series(self, **values) -> None:
        pass

    def close(self, status: str = "complete") -> None:
        pass

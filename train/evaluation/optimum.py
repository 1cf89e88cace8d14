"""The optimum every policy is measured against: minimum-energy plans per scenario, solved once and cached.

For each episode of a scenario set, :func:`optimal_energies` solves the minimum-energy problem of
:mod:`baselines.optimal` on the env's own grid (every command held over one ``dt``) from the start to
the goal by T_con, and caches the energy on disk, keyed by the start in the goal's frame, T_con, dt
and the limits, so that a second ``evaluate`` or ``compare`` does not solve again.

The cache is written as the optima are solved, a few at a time (an interrupted command keeps what it solved), and
merged under a file lock with an atomic replace, so two commands may solve and cache at once: each keeps the
other's optima and skips those the other has solved or is solving (each batch is claimed first). It lives in ``$DWR_GYM_CACHE`` (default
``~/.cache/dwr-gym``); delete it to solve afresh.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from dwr_gym import model

try:
    import fcntl
except ImportError:  # not POSIX: no lock and no claims (see _locked)
    fcntl = None  # type: ignore[assignment]
from dwr_gym.params import EnvParams
from train.evaluation.shipped_optima import problem_record, shipped_energies

#: Bump when the problem or the solver settings change, so that stale optima are not reused.
CACHE_VERSION = 2
#: Each optimum is solved on a problem of the next multiple of this many intervals, the last ones holding the robot still
#: at the goal (:func:`baselines.optimal.solve_minimum_energy`'s ``pad_to``): the same energy to 1e-9 (the solver's
#: tolerance). Building a solver takes about 1.5 ms per interval (a second at 700), a solve from the coarse plan some
#: 0.04 ms per interval: the 7 sizes of 200 to 1,400 intervals cost more per solve than the 52 of a multiple of 20,
#: and 4x less building, which is most of a batch's time (``python -m benchmarks run optimum-speed``).
PAD_TO = 200
#: Each optimum is searched first on commands held at most this long [s] (:func:`coarse_factor`), then refined from the
#: cheapest coarse plan (:func:`baselines.optimal.solve_plans`). At the env's dt (0.05 s: 20 periods a command, 10-70
#: intervals) 15-30 % less CPU time than 10 periods, the fine solves' iterations as they were (5.3 on average), the
#: 1,009 default optima within 4.7e-7 of the shipped ones; 40 periods miss 5 by more than 1e-6. Longer holds lead
#: the refinement into other local optima (at dt 0.25 s, 5-s commands found a plan 18 % cheaper than the search's).
COARSE_HOLD = 1.0


def coarse_factor(dt: float) -> int:
    """The control periods a command of the coarse grid holds: the most that divide :data:`PAD_TO` and last at most
    :data:`COARSE_HOLD` (1, no coarse search, where one period lasts longer)."""
    return max((k for k in range(1, PAD_TO + 1) if PAD_TO % k == 0 and k * dt <= COARSE_HOLD * (1.0 + 1e-9)), default=1)


COARSE = coarse_factor(0.05)  # at the env's dt: 20
#: fatrop's intervals per stage on the fine grid, the states inside a stage eliminated
#: (:func:`baselines.minimum_energy_nlp.minimum_energy_solver`; ``python -m benchmarks run optimum-speed``).
STAGE = 4
OPTIMA = ("pose", "position", "none")
BATCH_PER_WORKER = 32
"""Plans per solving thread between two writes of the cache: a few seconds of work, so an interruption loses little."""
CLAIM_WAIT = 1.0  # [s]
"""How often a process waiting for optima that another process is solving looks at the cache again."""


def cache_dir() -> Path:
    """Where optimal energies are cached: ``$DWR_GYM_CACHE``, else ``~/.cache/dwr-gym``."""
    return Path(os.environ.get("DWR_GYM_CACHE") or Path.home() / ".cache" / "dwr-gym")


def casadi_available() -> bool:
    """Whether the ``optimal`` extra (CasADi) is installed."""
    try:
        import casadi  # noqa: F401
    except ImportError:
        return False
    return True


def _cache_file(params: EnvParams, heading: bool) -> Path:
    key = json.dumps([CACHE_VERSION, params.dt, params.u_max, params.omega_max, heading])
    return cache_dir() / f"optimal-energy-{hashlib.sha256(key.encode()).hexdigest()[:16]}.json"


def _problem(params: EnvParams, heading: bool) -> dict[str, Any]:
    """The problem a cache file holds optima of (:func:`problem_record`), as a shipped file records it."""
    return problem_record(CACHE_VERSION, params.dt, params.u_max, params.omega_max, heading)


def _known(params: EnvParams, heading: bool) -> tuple[Path, dict[str, float | str]]:
    """The user's cache file for this problem and what is known of it: the shipped optima of the default sets
    (:mod:`train.evaluation.shipped_optima`), then the user's cache, which wins where both hold a key."""
    path = _cache_file(params, heading)
    return path, {**shipped_energies(path.name, _problem(params, heading)), **_read_cache(path)}


def _start_key(start: NDArray[np.float64], T_con: float) -> str:
    return ",".join(f"{v:.12e}" for v in (*start, T_con))


#: An optimum's problem: the start in the goal's frame, T_con [s], dt [s], u_max [m/s], omega_max [rad/s], heading.
EnergyJob = tuple[tuple[float, float, float], float, float, float, float, bool]


def _solve_energies(jobs: list[EnergyJob], workers: int, coarse: int | None = None, stage: int | None = None
                    ) -> list[float | str]:  # fmt: skip
    """The optimal energy of each job, or its error message (returned: one failure leaves the others intact), solved
    as one batch on ``workers`` threads (:func:`baselines.optimal.solve_plans`); ``coarse`` = 1: every guess searched
    on the fine grid (the whole search, some 5x slower)."""
    from baselines.optimal import Plan, solve_plans

    plans = solve_plans([{"start": start, "arrival_time": T_con, "dt": dt, "u_max": u_max, "omega_max": omega_max,
                          "heading": heading, "pad_to": PAD_TO, "coarse": coarse or coarse_factor(dt),
                          "stage": stage or STAGE}
                         for start, T_con, dt, u_max, omega_max, heading in jobs], workers)  # fmt: skip
    return [plan.energy if isinstance(plan, Plan) else str(plan) for plan in plans]


def _solve_energy(job: EnergyJob) -> float | str:
    """One optimum (a Ray task's work: each task one job)."""
    return _solve_energies([job], 1)[0]


def goal_frame_starts(starts: NDArray[np.float64], goals: NDArray[np.float64]) -> NDArray[np.float64]:
    """(N, 3) start poses in their goals' frames, where the optimal problem is posed."""
    x, y, psi = model.to_goal_frame(*np.asarray(starts, dtype=np.float64).T, *np.asarray(goals, dtype=np.float64).T)
    return np.stack([x, y, psi], axis=1)


def optimal_energies(
    params: EnvParams,
    starts: NDArray[np.float64],
    goals: NDArray[np.float64],
    T_cons: NDArray[np.float64] | None = None,
    *,
    heading: bool = True,
    workers: int = 0,
    progress: bool = False,
    description: str = "optimum",
    on_solved: Callable[[int], None] | None = None,
    address: str | None = None,
) -> tuple[NDArray[np.float64], list[str]]:
    """Minimum energy to reach each goal (the pose, or the position when ``heading`` is False) by T_con
    (each episode's ``T_cons``, default ``params.T_con``).

    Returns the energies (N,) and the messages of the episodes without an optimum (infeasible T_con
    or an IPOPT failure), whose energy is NaN. Solved in ``workers`` processes (0: every core, at
    most 8) and cached on disk as they are solved, a few at a time; two processes may share the cache.
    ``on_solved`` receives the number of optima solved (or found solved by another process) so far. With ``address``
    (``auto``, ``local``, a Ray cluster's address) they are solved as Ray tasks on that cluster
    (:class:`train.evaluation.ray_pool.RayPool`) instead.
    """
    local, T_cons, keys = _keys(params, starts, goals, T_cons)
    path, cache = _known(params, heading)
    missing = sorted({k: i for i, k in enumerate(keys) if k not in cache}.values())
    if missing:
        # the longest problems first, neighbours together: each process builds few solvers, none waits at the end
        missing.sort(key=lambda i: -T_cons[i])
        jobs = {keys[i]: (tuple(map(float, local[i])), float(T_cons[i]), params.dt, params.u_max, params.omega_max,
                          heading) for i in missing}  # fmt: skip
        cache.update(_solve_and_cache(jobs, path, workers, progress, description, on_solved, address))
    values = [cache[k] for k in keys]
    energies = np.array([v if isinstance(v, float) else math.nan for v in values])
    failures = [f"episode {i}: {v}" for i, v in enumerate(values) if not isinstance(v, float)]
    return energies, failures


def _keys(
    params: EnvParams, starts: NDArray[np.float64], goals: NDArray[np.float64], T_cons: NDArray[np.float64] | None
) -> tuple[NDArray[np.float64], NDArray[np.float64], list[str]]:
    """The starts in their goals' frames, each episode's T_con and the cache keys."""
    local = goal_frame_starts(starts, goals)
    T_cons = np.full(len(local), params.T_con) if T_cons is None else np.asarray(T_cons, dtype=np.float64)
    return local, T_cons, [_start_key(s, T) for s, T in zip(local, T_cons, strict=True)]


def cache_keys(
    params: EnvParams,
    starts: NDArray[np.float64],
    goals: NDArray[np.float64],
    T_cons: NDArray[np.float64] | None = None,
    *,
    heading: bool = True,
) -> tuple[str, dict[str, Any], list[str]]:
    """The name of the cache file of these episodes' problem, the problem (:func:`problem_record`) and each episode's
    key in it: what ``python -m benchmarks run ship-optima`` ships."""
    return _cache_file(params, heading).name, _problem(params, heading), _keys(params, starts, goals, T_cons)[2]


def missing_optima(
    params: EnvParams,
    starts: NDArray[np.float64],
    goals: NDArray[np.float64],
    T_cons: NDArray[np.float64] | None = None,
    *,
    heading: bool = True,
) -> set[tuple[str, str]]:
    """The optima :func:`optimal_energies` would solve (not cached yet), as (cache file, key) pairs: what a command
    will solve is the union of its sets' (the disturbed sets share the random set's starts)."""
    path, cache = _known(params, heading)
    return {(path.name, k) for k in _keys(params, starts, goals, T_cons)[2] if k not in cache}


def _read_cache(path: Path) -> dict[str, float | str]:
    try:
        return dict(json.loads(path.read_text()))
    except (OSError, ValueError, TypeError):
        return {}


@contextmanager
def _locked(path: Path) -> Iterator[None]:
    """An exclusive lock of the cache file ``path`` between processes (POSIX ``flock`` on a ``.lock`` beside it;
    where there is none, the atomic replace alone: two processes writing at once may then lose one's optima)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    if fcntl is None:
        yield
        return
    with path.with_suffix(".lock").open("a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def _replace(path: Path, data: dict[str, Any]) -> None:
    temporary = path.with_suffix(f".{os.getpid()}.tmp")
    temporary.write_text(json.dumps(data))
    os.replace(temporary, path)


def _running(pid: int) -> bool:
    """Whether process ``pid`` still runs (POSIX only: it is asked where ``fcntl`` exists)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _claims(path: Path, cache: dict[str, float | str]) -> dict[str, int]:
    """The keys being solved by running processes (``<cache>.claims`` beside the cache), without those cached."""
    if fcntl is None:
        return {}
    claimed = _read_cache(path.with_suffix(".claims"))
    return {k: int(pid) for k, pid in claimed.items() if k not in cache and _running(int(pid))}  # type: ignore[arg-type]


def _claim(path: Path, todo: list[str], size: int) -> tuple[list[str], dict[str, float | str], set[int]]:
    """Under the lock: the next ``size`` keys of ``todo`` neither cached nor being solved by another running process,
    now claimed by this one; the cache as it is; the processes solving the rest of ``todo``."""
    with _locked(path):
        cache = _read_cache(path)
        claims = _claims(path, cache)
        batch = [k for k in todo if k not in cache and k not in claims][:size]
        if fcntl is not None:
            _replace(path.with_suffix(".claims"), {**claims, **dict.fromkeys(batch, os.getpid())})
    wanted = set(todo)
    others = {pid for k, pid in claims.items() if k in wanted and pid != os.getpid()}
    return batch, cache, others


def _merge_into_cache(path: Path, found: dict[str, float | str], release: bool = False) -> dict[str, float | str]:
    """Add ``found`` to the cache file, reading, merging and replacing it atomically under the lock, so that two
    processes writing at once both keep what they solved; their claims go (with ``release``, all of this process's).
    Returns the merged cache (what others solved too)."""
    with _locked(path):
        cache = _read_cache(path)
        if found:
            cache.update(found)
            _replace(path, cache)
        if fcntl is not None:
            claims = {k: pid for k, pid in _claims(path, cache).items() if not (release and pid == os.getpid())}
            _replace(path.with_suffix(".claims"), claims)
    return cache


def _solve_and_cache(
    jobs: dict[str, Any],
    path: Path,
    workers: int,
    progress: bool,
    description: str,
    on_solved: Callable[[int], None] | None = None,
    address: str | None = None,
) -> dict[str, float | str]:
    """Solve ``jobs`` (by cache key) in batches of a few seconds' work, merging each batch into the cache file as it
    ends. Each batch is claimed first, so that two processes solving the same episodes share the work: each skips
    what the other solved or is solving, and waits for the other's last batch. An interruption (Ctrl-C) keeps every
    optimum solved before it. Returns the results by key."""
    workers = workers or min(os.cpu_count() or 1, 8)
    bar: Any = None
    if progress:
        from train.progress import Progress

        bar = Progress(total=len(jobs), desc=description, unit="plan", leave=False)
    found: dict[str, float | str] = {}
    pending: dict[str, float | str] = {}
    pool: Any = None
    shared = True  # False once the cache cannot be written: the optima are still returned, just not kept
    waiting_noted = False

    solved_count = 0

    def tick() -> None:
        nonlocal solved_count
        solved_count += 1
        if bar is not None:
            bar.update()
        if on_solved is not None:
            on_solved(solved_count)

    def take(known: dict[str, float | str]) -> None:
        for key in [key for key in todo if key in known]:  # solved by another process
            found[key] = known[key]
            todo.remove(key)
            tick()

    def flush(release: bool = False) -> None:
        nonlocal shared
        if shared and (pending or release):
            try:
                take(_merge_into_cache(path, pending, release))
            except OSError as error:
                print(f"warning: could not cache optimal energies in {path.parent}: {error}", file=sys.stderr)
                shared = False
        found.update(pending)
        pending.clear()

    todo = list(jobs)
    try:
        if address is not None:
            from train.evaluation.ray_pool import RayPool

            pool = RayPool(address)
            workers = pool.workers
        while todo:
            size, batch, others = BATCH_PER_WORKER * workers, [], set()
            if shared:
                try:
                    batch, cache, others = _claim(path, todo, size)
                    take(cache)
                except OSError as error:  # a read-only home: solved here alone, not kept
                    print(f"warning: could not cache optimal energies in {path.parent}: {error}", file=sys.stderr)
                    shared = False
            if not shared:
                batch = todo[:size]
            if not batch:
                if todo and not waiting_noted:
                    print(f"\n{description}: waiting for {len(todo)} optima that process(es) "
                          f"{', '.join(map(str, sorted(others)))} are solving", file=sys.stderr)  # fmt: skip
                    waiting_noted = True
                time.sleep(CLAIM_WAIT)
                continue
            for key in batch:
                todo.remove(key)
            solved = _solve_energies([jobs[k] for k in batch], workers) if pool is None else pool.map(
                _solve_energy, (jobs[k] for k in batch), chunksize=-(-len(batch) // workers))  # fmt: skip
            for key, result in zip(batch, solved, strict=True):
                pending[key] = result
                tick()
            flush()
    finally:
        flush(release=True)  # also on Ctrl-C: what was solved is kept, this process's claims go
        if pool is not None:
            pool.shutdown(wait=False, cancel_futures=True)
        if bar is not None:
            bar.close()
    return found


def solve_uncached(
    jobs: list[EnergyJob],
    workers: int = 0,
    on_solved: Callable[[int], None] | None = None,
    coarse: int | None = None,
    stage: int | None = None,
) -> list[float | str]:
    """Solve each job (start in the goal's frame, T_con, dt, u_max, omega_max, heading) afresh on ``workers``
    threads (0: every core, at most 8), reading and writing no cache: the energy, or why there is none.
    ``on_solved`` receives the number solved so far (what ``dwr-gym optimum verify`` re-solves); ``coarse`` = 1
    searches every guess on the fine grid instead of refining the cheapest coarse plan (default: :func:`coarse_factor`
    of each job's dt); ``stage``: fatrop's intervals per stage on the fine grid (default :data:`STAGE`)."""
    workers = workers or min(os.cpu_count() or 1, 8)
    results: list[float | str] = []
    size = BATCH_PER_WORKER * workers
    for first in range(0, len(jobs), size):  # a batch of a few seconds' work between two reports
        results.extend(_solve_energies(jobs[first : first + size], workers, coarse, stage))
        if on_solved is not None:
            on_solved(len(results))
    return results


__all__ = [
    "OPTIMA",
    "PAD_TO",
    "cache_dir",
    "cache_keys",
    "casadi_available",
    "goal_frame_starts",
    "missing_optima",
    "optimal_energies",
    "solve_uncached",
]

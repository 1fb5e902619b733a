"""Run a study's variants on Dask and keep their rows in Parquet as they complete.

Work units are whole variants (:func:`ffrf.studies.variant.run_variant`). Without a scheduler address the
runner starts a :class:`dask.distributed.LocalCluster` of one single-threaded worker process per core (or
``workers``); with ``scheduler = "tcp://host:8786"`` it submits to that cluster, nothing else changed. Rows are
collected as futures complete (``as_completed``) and written in batches, each a Parquet file
``DIR/rows/part-*.parquet`` written under a temporary name and renamed (a reader never sees half a file).
A rerun reads the ids already in ``DIR/rows`` and submits only the others, so a Ctrl-C (the buffer is written on
the way out; ``python -m ffrf study`` then ends with one line and exit status 130) or a killed client loses at
most the variants in flight and the rows of the last ``flush_seconds``. A worker that dies has its variant rerun
by the scheduler elsewhere; a variant that could not be computed at all (its worker died too often) writes no row,
so a rerun tries it again. A variant that fails (no assembly, Newton divergence, bad parameters) is a row with its
reason. A folder that holds another
study's rows (another name, base or parameter columns in its ``study.json``) is refused before anything runs.

A worker keeps its scene cache (:data:`ffrf.scenes.scene_cache.PROCESS_CACHE`) between the variants it runs, and
its allocator is kept from returning every large array to the system (:func:`_allocator_for_variants`).
"""

from __future__ import annotations

import ctypes
import json
import logging
import os
import time
import uuid
from collections.abc import Iterable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.parquet as pq
from distributed.diagnostics.plugin import WorkerPlugin

from ffrf.errors import SceneError
from ffrf.scenes.kernel_warmup import warm_kernels
from ffrf.scenes.scene_cache import code_version
from ffrf.studies.sampling import Variant, study_design
from ffrf.studies.spec import Study
from ffrf.studies.variant import output_names, row_names, run_variant

__all__ = [
    "ROWS",
    "WORKER_WAIT",
    "KernelWarmup",
    "StudyCounts",
    "check_scheduler_file",
    "finished_ids",
    "pending",
    "read_rows",
    "row_schema",
    "run_study",
]

log = logging.getLogger(__name__)

#: The folder of row files under a study's output folder.
ROWS = "rows"


@dataclass(frozen=True)
class StudyCounts:
    """What one call of :func:`run_study` did: variants in the design, already finished before, run now (ok and
    failed rows written) and lost (no row: the worker died too often, or the run was interrupted), and its wall time.

    Counts, not a run: no time histories, so not a :class:`~ffrf.output.result.Result`. What the variants computed
    is in their rows, each derived from its run's Result by :func:`ffrf.studies.variant.row_outputs`."""

    design: int
    skipped: int
    ok: int
    failed: int
    lost: int
    wall_time_s: float


def row_schema(study: Study) -> pa.Schema:
    """The Arrow schema of a study's rows (:func:`ffrf.studies.variant.row_names`)."""
    types: dict[str, pa.DataType] = {
        "id": pa.string(),
        "block": pa.string(),
        "sample": pa.int64(),
        "status": pa.string(),
        "end": pa.string(),
        "reason": pa.string(),
        "assembles": pa.bool_(),
        "worker": pa.string(),
    }
    return pa.schema([(name, types.get(name, pa.float64())) for name in row_names(study)])


def read_rows(directory: str | Path) -> pa.Table | None:
    """Every row written under ``DIR/rows``, each id once (the first written), or ``None`` before any."""
    parts = sorted((Path(directory) / ROWS).glob("part-*.parquet"))
    if not parts:
        return None
    table = pa.concat_tables([pq.read_table(p) for p in parts], promote_options="default")
    ids = table.column("id").to_pylist()
    first: dict[str, int] = {}
    for k, i in enumerate(ids):
        first.setdefault(i, k)
    return table.take(sorted(first.values())) if len(first) < len(ids) else table


def finished_ids(directory: str | Path) -> set[str]:
    """Ids of the variants with a row under ``DIR/rows``."""
    parts = sorted((Path(directory) / ROWS).glob("part-*.parquet"))
    return {i for p in parts for i in pq.read_table(p, columns=["id"]).column("id").to_pylist()}


def _write_batch(rows: list[dict], schema: pa.Schema, directory: Path) -> None:
    """One Parquet file of ``rows``, renamed into place once complete."""
    if not rows:
        return
    folder = directory / ROWS
    folder.mkdir(parents=True, exist_ok=True)
    name = f"part-{time.strftime('%Y%m%dT%H%M%S')}-{uuid.uuid4().hex[:8]}.parquet"
    table = pa.Table.from_pylist(rows, schema=schema)
    partial = folder / f".{name}.tmp"
    pq.write_table(table, partial)
    os.replace(partial, folder / name)


#: glibc's ``mallopt`` parameters (``<malloc.h>``) and the values :func:`_allocator_for_variants` sets: those glibc's
#: dynamic thresholds reach in a long-running process (the mmap threshold's dynamic maximum on 64 bits).
M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3
MMAP_THRESHOLD, TRIM_THRESHOLD = 32 * 2**20, 64 * 2**20
#: Set by Dask's nanny for the workers it spawns (``distributed.nanny.pre-spawn-environ``).
TRIM_VARIABLE = "MALLOC_TRIM_THRESHOLD_"
_ALLOCATOR_SET: list[bool] = []


def _allocator_for_variants() -> None:
    """Undo, in a worker process, what Dask's nanny's ``MALLOC_TRIM_THRESHOLD_=65536`` does to glibc's allocator.

    Set in the environment, a trim threshold also pins the mmap threshold at 128 KiB (glibc stops adapting it), so
    every array above 128 KiB is mapped afresh and unmapped when freed, and the heap above 64 KiB of free memory is
    returned at once: a variant's arrays are then page-faulted in again and again (measured by
    ``bench/study_speed.py``: ``docs/studies.md``, "Speed").
    :func:`_client` starts its local workers without the variable; a worker of another cluster that has it gets
    glibc's thresholds set here as a long-running process reaches them (:data:`MMAP_THRESHOLD`,
    :data:`TRIM_THRESHOLD`), once per process; elsewhere (no glibc) nothing is done."""
    if _ALLOCATOR_SET or TRIM_VARIABLE not in os.environ:
        return
    _ALLOCATOR_SET.append(True)
    try:
        libc = ctypes.CDLL("libc.so.6")
    except OSError:
        return
    if libc.mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD) and libc.mallopt(M_TRIM_THRESHOLD, TRIM_THRESHOLD):
        log.info(
            "worker %d: glibc mmap and trim thresholds set to %d and %d bytes",
            os.getpid(),
            MMAP_THRESHOLD,
            TRIM_THRESHOLD,
        )


class _CancelledQuietly(logging.Filter):
    """Drops a worker's warning that a task it ran was cancelled: what the run's Ctrl-C does on purpose (its client
    cancels the variants in flight), not news to the user, who is told in one line (:mod:`ffrf.cli`)."""

    def filter(self, record: logging.LogRecord) -> bool:
        return "CancelledError" not in record.getMessage()


def _worker_variant(study: Study, variant: Variant) -> dict:
    """A variant's row (:func:`ffrf.studies.variant.run_variant`) on a Dask worker, its allocator set first."""
    _allocator_for_variants()
    state = logging.getLogger("distributed.worker.state_machine")
    if not any(isinstance(f, _CancelledQuietly) for f in state.filters):
        state.addFilter(_CancelledQuietly())
    return run_variant(study, variant)


def check_scheduler_file(path: str | Path) -> None:
    """Refuse a scheduler file that is not there yet (:class:`SceneError` naming the fix)."""
    if not Path(path).is_file():
        raise SceneError(
            f"scheduler file {path} not found: start the scheduler with --scheduler-file {path} first (its batch "
            "job), or give its address with --scheduler"
        )


def _client(scheduler: str | None, workers: int | None, scheduler_file: str | None = None) -> tuple[Any, Any]:
    """A Dask client of the scheduler at ``scheduler`` or written in ``scheduler_file`` (by ``dask scheduler
    --scheduler-file``, as a batch job starts one), or of a new local cluster (returned to close it) whose workers
    start without Dask's ``MALLOC_TRIM_THRESHOLD_`` (:func:`_allocator_for_variants` says why)."""
    import dask
    from dask.distributed import Client, LocalCluster

    # Dask logs every worker's start and end at INFO; show them only when the caller asked for INFO (-v).
    logging.getLogger("distributed").setLevel(max(logging.WARNING, logging.getLogger().getEffectiveLevel()))
    if scheduler_file is not None:
        check_scheduler_file(scheduler_file)
        return Client(scheduler_file=scheduler_file), None
    if scheduler is not None:
        return Client(scheduler), None
    with dask.config.set({f"distributed.nanny.pre-spawn-environ.{TRIM_VARIABLE}": None}):  # read by each nanny
        cluster = LocalCluster(
            n_workers=workers or os.cpu_count() or 1, threads_per_worker=1, processes=True, dashboard_address=None
        )
    return Client(cluster), cluster


def _progress(total: int, enabled: bool) -> Any:
    """A tqdm bar (rate and ETA) on stderr, or a stand-in that counts silently."""
    from tqdm import tqdm

    return tqdm(total=total, unit="variant", disable=not enabled, smoothing=0.05)


def _description(study: Study) -> dict:
    """What ``DIR/study.json`` says of a study (the report reads it)."""
    return {
        "name": study.name,
        "method": study.method,
        "samples": study.samples,
        "seed": study.seed,
        "parameters": [asdict(p) for p in study.parameters],
        "outputs": list(output_names(study.n_links, study.stability)),
        "limits": [list(limit) for limit in study.limits],
        "base": study.base.description(),
        "bore_error_model": study.base.bore_error_model,
        "fingerprint": study.fingerprint,
        "solver": code_version(),
        "variants": len({v.id for v in study_design(study)}),
    }


#: What makes a folder's rows another study's: its name, its base, the parameters' columns and the solver that
#: computed them (its sources and libraries, :func:`~ffrf.scenes.scene_cache.code_version`). A rerun may change the
#: design only so that every row already there stays one of its variants (:func:`_check_one_design`).
SAME_STUDY = ("name", "base", "bore_error_model", "fingerprint", "solver")
COLUMN = ("name", "target", "joint", "link")


def _check_same_study(study: Study, directory: Path) -> None:
    """Refuse a folder whose ``study.json`` is of another study (:data:`SAME_STUDY`), before anything runs: its rows
    would be mixed with this study's."""
    path = directory / "study.json"
    if not path.is_file():
        return
    try:
        old = json.loads(path.read_text())
    except (OSError, ValueError):
        old = {}
    new = json.loads(json.dumps(_description(study)))  # as the file would hold it
    differs = [key for key in SAME_STUDY if old.get(key) != new[key]]
    columns = [[p.get(k) for k in COLUMN] for p in old.get("parameters", [])]
    if columns != [[p[k] for k in COLUMN] for p in new["parameters"]]:
        differs.append("parameters")
    if differs == ["solver"]:
        raise SceneError(
            f"{directory} holds rows computed by another version of the solver (its sources or libraries changed "
            "since): they would mix with this version's; give another output folder (--out), or delete "
            f"{directory} to start afresh"
        )
    if differs:
        raise SceneError(
            f"{directory} holds the rows of another study ({old.get('name', '?')!r}: its {', '.join(differs)} "
            f"differ from {study.name!r}); give another output folder (--out), or delete {directory} to start afresh"
        )


def _check_one_design(study: Study, directory: Path) -> None:
    """Refuse a folder holding rows that are not variants of this study's design (another seed, size or method of
    a random design: its rows would bias every estimate of this one); a design that keeps every row there (a resumed
    study, a grid grown by values, the first draws of a longer random sequence) is accepted."""
    stray = finished_ids(directory) - {v.id for v in study_design(study)}
    if stray:
        raise SceneError(
            f"{directory} holds {len(stray)} row(s) of another design of this study (another seed, number of "
            "samples, method or distribution): they would mix with this design's; give another output folder "
            f"(--out), or delete {directory} to start afresh"
        )


#: Seconds a study waits for the first worker of a scheduler it did not start before it says so.
WORKER_WAIT = 60.0


class KernelWarmup(WorkerPlugin):
    """A Dask worker plugin: each worker compiles or loads the solver's kernels once, when it joins, before its first
    variant (:func:`~ffrf.scenes.kernel_warmup.warm_kernels`), so that no variant's time counts a compilation."""

    name = "ffrf-kernel-warmup"

    def setup(self, worker: Any) -> None:
        warm_kernels()


def _check_workers(client: Any, wait: float = WORKER_WAIT) -> None:
    """Wait up to ``wait`` seconds for a first worker (a scheduler without workers is named, not waited on forever),
    then refuse workers that run another version of the solver than this client (their rows would not be this
    version's): each one's :func:`~ffrf.scenes.scene_cache.code_version` against ours."""
    try:
        client.wait_for_workers(1, timeout=wait)
    except TimeoutError:
        raise SceneError(
            f"the scheduler at {client.scheduler.address} has no worker after {wait:g} s: start workers on it "
            f"(dask worker {client.scheduler.address}, or the batch jobs that do), then run the study again"
        ) from None
    ours = code_version()
    others = sorted(address for address, version in client.run(code_version).items() if version != ours)
    if others:
        raise SceneError(
            f"worker(s) {', '.join(others)} run another version of the solver than this client (their sources or "
            "libraries differ): install the same version on every worker, or start the study where they agree"
        )


def pending(study: Study, directory: Path) -> tuple[list[Variant], int, int]:
    """The variants still to run (each id once), the design's size and how many are finished."""
    design = study_design(study)
    done = finished_ids(directory)
    todo: dict[str, Variant] = {}
    for variant in design:
        if variant.id not in done:
            todo.setdefault(variant.id, variant)
    return list(todo.values()), len(design), len({v.id for v in design} & done)


def run_study(
    study: Study,
    directory: str | Path,
    scheduler: str | None = None,
    workers: int | None = None,
    client: Any = None,
    batch: int = 50,
    flush_seconds: float = 10.0,
    progress: bool = True,
    scheduler_file: str | None = None,
    worker_wait: float = WORKER_WAIT,
) -> StudyCounts:
    """Run every unfinished variant of ``study`` into ``directory`` (module docstring): on ``client`` if given,
    else on the scheduler at ``scheduler`` or in ``scheduler_file``, else on a new local cluster of ``workers``
    processes. Every worker warms its kernels when it joins (:class:`KernelWarmup`); a scheduler without a worker
    after ``worker_wait`` seconds, or a worker of another solver version, is refused (:class:`SceneError`)."""
    from dask.distributed import as_completed

    started = time.perf_counter()
    directory = Path(directory)
    _check_same_study(study, directory)
    _check_one_design(study, directory)
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "study.json").write_text(json.dumps(_description(study), indent=2))
    todo, size, skipped = pending(study, directory)
    schema = row_schema(study)
    counts = {"ok": 0, "failed": 0, "lost": 0}
    if not todo:
        return StudyCounts(size, skipped, 0, 0, 0, time.perf_counter() - started)
    own = client is None
    cluster = None
    if own:
        client, cluster = _client(scheduler, workers, scheduler_file)
    buffer: list[dict] = []
    last = time.monotonic()
    bar = _progress(len(todo), progress)
    futures: Iterable[Any] = []
    try:
        _check_workers(client, worker_wait)
        client.register_plugin(KernelWarmup(), name=KernelWarmup.name)
        shared = client.scatter(study, broadcast=True)
        futures = [client.submit(_worker_variant, shared, v, key=f"variant-{study.fingerprint}-{v.id}") for v in todo]
        for future in as_completed(futures):
            if future.status == "finished":
                row = future.result()
                buffer.append(row)
                counts["ok" if row["status"] == "ok" else "failed"] += 1
            else:  # the scheduler gave up on it (its workers died): no row, a rerun tries again
                counts["lost"] += 1
                log.warning("variant %s lost: %s", future.key, future.exception())
            future.release()
            bar.update(1)
            if len(buffer) >= batch or time.monotonic() - last > flush_seconds:
                _write_batch(buffer, schema, directory)
                buffer, last = [], time.monotonic()
    finally:  # also on Ctrl-C: keep what completed, cancel what did not
        _write_batch(buffer, schema, directory)
        bar.close()
        if own:
            client.cancel(list(futures))
            client.close()
            if cluster is not None:
                cluster.close()
    lost = counts["lost"] + len(todo) - sum(counts.values())
    return StudyCounts(size, skipped, counts["ok"], counts["failed"], lost, time.perf_counter() - started)

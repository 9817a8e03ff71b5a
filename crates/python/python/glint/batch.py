"""glint.batch: a whole study on Dask, with the table and report of ``glint batch``.

``glint.batch(inputs, scene, views, out)`` (or ``glint.batch.run``) finds the inputs as
``glint batch`` does (files, directories, glob patterns, BIDS datasets), sends each
input's path and the scene to a ``dask.distributed`` cluster, where a worker reads the
volume from shared storage and makes its mosaic (and slices) with one renderer, then
writes ``out/results.jsonl`` and ``out/index.html``. Without a ``client`` it starts a
``LocalCluster`` of worker processes on this machine; with one it runs on that cluster
(``Client("tcp://scheduler:8786")``, a ``dask_jobqueue.SLURMCluster``'s client).

Everything but the distribution is glint's Rust library (``glint_batch``): the
discovery, the per-input job (idempotent, atomic writes, a failed row rather than an
exception for a bad input, skipped when up to date) and the report writer, so the
command line and this module are interchangeable on one output directory.

From the shell::

    python -m glint.batch INPUT... -o OUT [--scene s.json] [--views left,anterior,superior]
        [--slices] [--force] [--scheduler tcp://host:8786 | --workers N]

Dask is optional: ``pip install glint[dask]``.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import types
from typing import Any, Callable, Iterable, Optional, Sequence, Union

from glint import _glint
from glint._glint import Scene

__all__ = ["DEFAULT_VIEWS", "job", "run", "main"]

#: The views of a mosaic unless told, as ``glint batch``'s.
DEFAULT_VIEWS = ("left", "anterior", "superior")

#: The highest exit status of ``python -m glint.batch`` that counts failed inputs.
MAX_FAILED_STATUS = 100

PathLike = Union[str, "os.PathLike[str]"]


def job(item: dict, scene: Optional[Scene], views: Sequence[str], out: str,
        slices: bool = False, force: bool = False, strict: bool = False) -> dict:
    """One input's job, run by a worker: ``{"row": row, "skipped": bool}``.

    ``item`` is one of ``glint._glint.batch_inputs``'s dicts. The work is the Rust
    library's (``glint_batch::run_job``), with the GIL released.
    """
    row, skipped = _glint.batch_job(item, scene, list(views), out, slices, force, strict)
    return {"row": row, "skipped": skipped}


def _scene(scene: Union[Scene, PathLike, None]) -> Optional[Scene]:
    """A glint.Scene, a scene file's path (read as ``glint render --scene`` does), or None."""
    if scene is None or isinstance(scene, Scene):
        return scene
    return Scene.load(os.fspath(scene))


def _local_client(workers: Optional[int]):
    """A client of a new LocalCluster: one single-threaded worker process per core
    (each input's render uses all of glint's threads)."""
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError("glint.batch needs dask.distributed: pip install glint[dask]") from e
    cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1,
                           processes=True, dashboard_address=None)
    return Client(cluster), cluster


class _Progress:
    """Inputs done, failed, and the time left, on one line of stderr."""

    def __init__(self, total: int, show: bool):
        self.total, self.show = total, show
        self.done = self.failed = 0
        self.start = time.monotonic()

    def update(self, outcome: dict) -> None:
        self.done += 1
        self.failed += outcome["row"]["status"] == "failed"
        if not self.show:
            return
        elapsed = time.monotonic() - self.start
        left = elapsed / self.done * (self.total - self.done)
        sys.stderr.write(f"\rglint.batch: {self.done}/{self.total} inputs, {self.failed} failed, "
                         f"ETA {int(left) // 60}:{int(left) % 60:02d} ")
        if self.done == self.total:
            sys.stderr.write("\n")
        sys.stderr.flush()


def run(inputs: Union[PathLike, Iterable[PathLike]], scene: Union[Scene, PathLike, None] = None,
        views: Sequence[str] = DEFAULT_VIEWS, out: PathLike = "glint-batch", *,
        client: Any = None, slices: bool = False, force: bool = False, strict: bool = False,
        bids_suffix: Optional[Sequence[str]] = None, workers: Optional[int] = None,
        retries: int = 1, progress: Optional[bool] = None,
        on_result: Optional[Callable[[dict], None]] = None) -> dict:
    """Renders a study on Dask; returns ``{"ok", "failed", "skipped", "rows"}``.

    ``inputs``: paths, directories, glob patterns or BIDS roots (as ``glint batch``);
    ``scene``: a ``glint.Scene``, a scene file or None (the default scene); ``views``:
    the mosaic's views; ``out``: the output directory (every worker must see it).
    ``client``: a ``dask.distributed.Client`` (None: a LocalCluster of ``workers``
    processes, one per core by default, closed at the end). A task that raises is tried
    ``retries`` more times; a task whose workers die is moved by Dask to another worker
    (its outputs are written atomically, so a half-made input leaves nothing behind);
    one that can never finish becomes a failed row. ``progress``: a line on stderr
    (None: when stderr is a terminal); ``on_result(outcome)`` is called in this process
    as each input finishes. Rows are ``results.jsonl``'s, sorted by id.
    """
    if isinstance(inputs, (str, os.PathLike)):
        inputs = [inputs]
    out = os.path.abspath(os.fspath(out))
    items = _glint.batch_inputs([os.fspath(p) for p in inputs],
                                list(bids_suffix) if bids_suffix else None, out)
    scene = _scene(scene)
    views = [str(v) for v in views]
    # Check the scene and views here, before any task is sent.
    _glint.batch_spec_key(scene, views, slices, strict)
    os.makedirs(out, exist_ok=True)
    own = None
    if client is None:
        client, cluster = _local_client(workers)
        own = (client, cluster)
    try:
        from dask.distributed import as_completed

        futures = client.map(job, items, scene=scene, views=views, out=out, slices=slices,
                             force=force, strict=strict, pure=False, retries=retries)
        item_of = {f.key: item for f, item in zip(futures, items)}
        shown = sys.stderr.isatty() if progress is None else progress
        bar = _Progress(len(items), shown)
        outcomes = []
        for future in as_completed(futures):
            try:
                outcome = future.result()
            except Exception as e:  # every try failed, e.g. KilledWorker: one failed row
                item = item_of[future.key]
                line = f"the task failed on the cluster: {type(e).__name__}: {e}"
                row = _glint.batch_failed_row(item, scene, views, line, slices, strict)
                outcome = {"row": row, "skipped": False}
            outcomes.append(outcome)
            bar.update(outcome)
            if on_result is not None:
                on_result(outcome)
    finally:
        if own is not None:
            own[0].close()
            own[1].close()
    rows = sorted((o["row"] for o in outcomes), key=lambda r: r["id"])
    summary = _glint.batch_finish(out, rows)
    summary["skipped"] = sum(o["skipped"] for o in outcomes)
    summary["rows"] = rows
    return summary


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(
        prog="python -m glint.batch",
        description="A whole study on Dask: a mosaic of views (and QC slices) per input, "
                    "results.jsonl and index.html, as glint batch writes them.")
    ap.add_argument("inputs", nargs="+", metavar="INPUT",
                    help="files, directories, glob patterns (quoted) or BIDS datasets")
    ap.add_argument("-o", "--output", required=True, metavar="DIR", help="output directory")
    ap.add_argument("--scene", metavar="FILE", help="scene file (glint render --dump-scene)")
    ap.add_argument("--preset", help="transfer-function preset (replaces the scene's)")
    ap.add_argument("--size", metavar="WxH", help="size of each view, e.g. 256x256")
    ap.add_argument("--views", default=",".join(DEFAULT_VIEWS),
                    help="views of the mosaic, comma-separated (default: %(default)s)")
    ap.add_argument("--slices", action="store_true", help="also three orthogonal slices")
    ap.add_argument("--bids-suffix", default="", metavar="SUFFIX,...",
                    help="BIDS anat/ suffixes to take (default: the anatomical ones)")
    ap.add_argument("--force", action="store_true", help="make every input again")
    ap.add_argument("--strict", action="store_true", help="refuse what lenient readers accept")
    ap.add_argument("--scheduler", metavar="ADDRESS",
                    help="a running Dask scheduler (tcp://host:8786); default: a LocalCluster")
    ap.add_argument("--workers", type=int, help="LocalCluster worker processes (default: cores)")
    ap.add_argument("-q", "--quiet", action="store_true", help="no progress line")
    return ap


def main(argv: Optional[Sequence[str]] = None) -> int:
    """``python -m glint.batch``; returns the exit status: the number of failed inputs
    (at most 100), 1 with one line on stderr when the run cannot start."""
    args = _parser().parse_args(argv)
    try:
        scene = _scene(args.scene) or Scene()
        fields: dict = {}
        if args.preset:
            fields["preset"] = args.preset
        if args.size:
            w, _, h = args.size.lower().partition("x")
            fields["size"] = [int(w), int(h)]
        if fields:
            scene = scene.replace(**fields)
        client = None
        if args.scheduler:
            from dask.distributed import Client

            client = Client(args.scheduler)
        try:
            summary = run(args.inputs, scene, [v for v in args.views.split(",") if v],
                          args.output, client=client, slices=args.slices, force=args.force,
                          strict=args.strict, workers=args.workers,
                          bids_suffix=[s for s in args.bids_suffix.split(",") if s] or None,
                          progress=False if args.quiet else None)
        finally:
            if client is not None:
                client.close()
    except (OSError, ValueError, ImportError) as e:
        print(f"glint.batch: error: {e}", file=sys.stderr)
        return 1
    for row in summary["rows"]:
        if row["error"] and not args.quiet:
            print(f"glint.batch: {row['id']}: {row['error']}", file=sys.stderr)
    if not args.quiet:
        print(f"glint.batch: {len(summary['rows'])} inputs: {summary['ok']} made "
              f"({summary['skipped']} up to date), {summary['failed']} failed; report "
              f"{os.path.join(args.output, 'index.html')}", file=sys.stderr)
    return min(summary["failed"], MAX_FAILED_STATUS)


class _CallableModule(types.ModuleType):
    """``glint.batch(...)`` is ``glint.batch.run(...)``."""

    def __call__(self, *args, **kwargs):
        return run(*args, **kwargs)


if __name__ == "__main__":
    # Run the module as glint.batch, not __main__, so the tasks it sends name
    # glint.batch.job, which the workers import.
    from glint.batch import main as _main

    sys.exit(_main())
else:
    sys.modules[__name__].__class__ = _CallableModule

"""Running a study on Dask: a list of small picklable task specs mapped on a
``dask.distributed.Client``, records appended to a CSV as tasks finish, resumable.

* Each spec is a dict with a unique ``spec_id``; the task is a module-level function
  ``task(spec) -> dict`` (workers import it), so nothing depends on the client's machine.
* Records are appended to ``out`` (CSV, a fixed column list per study) and flushed to disk as each
  task finishes: a killed study keeps what it has; a rerun with the same ``out`` skips the specs
  already there (resume) and never writes a spec twice.
* ``retries``: a task whose worker dies is run again elsewhere (the record is written once, by the
  client). A task that raises is recorded with ``status = "error"`` and its message, not lost.
* The default client is a ``LocalCluster`` of process workers with one thread each (the Rust work
  releases the GIL; ``RAYON_NUM_THREADS=1`` keeps Rust's own pool to that thread too); pass a ``Client`` or a scheduler address to use an existing cluster.
"""

from __future__ import annotations

import csv
import io
import os
import time
import traceback
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from rss6.errors import InvalidInputError

__all__ = ["probe_task", "read_records", "run_study"]

Task = Callable[[Mapping[str, Any]], dict[str, Any]]


def _guarded(task: Task, spec: Mapping[str, Any]) -> dict[str, Any]:
    """Runs one task on a worker; an exception becomes an error record (a lost worker is not an
    exception here: Dask retries the task)."""
    t0 = time.perf_counter()
    try:
        rec = dict(task(spec))
        rec.setdefault("status", "ok")
    except Exception as e:  # recorded, not lost: the study goes on
        rec = {
            "status": "error",
            "error": f"{type(e).__name__}: {e}",
            "traceback": traceback.format_exc(limit=3),
        }
    rec["spec_id"] = str(spec["spec_id"])
    rec.setdefault("seconds", time.perf_counter() - t0)
    rec["worker_pid"] = os.getpid()
    return rec


def probe_task(spec: Mapping[str, Any]) -> dict[str, Any]:
    """A task that sleeps ``spec["sleep"]`` s and returns its spec's ``value`` — for tests of the
    engine (killed workers, killed parents, resume)."""
    time.sleep(float(spec.get("sleep", 0.0)))
    return {"value": spec.get("value", 0)}


def read_records(out: str | Path) -> list[dict[str, str]]:
    """The records in a study file (empty if it does not exist); a partly written last line (the
    process was killed while writing it) is dropped."""
    path = Path(out)
    if not path.exists():
        return []
    try:
        with path.open(newline="", encoding="utf-8") as f:
            text = f.read()
    except UnicodeDecodeError:
        raise InvalidInputError(f"{path} is not a study's records file (not UTF-8 text)") from None
    if text and "spec_id" not in next(csv.reader(text.splitlines()[:1]), []):
        # Appending under another file's header would make every record unreadable.
        raise InvalidInputError(
            f"{path} is not a study's records file (its first line has no spec_id column)"
        )
    if text and not text.endswith("\n"):
        text = text[: text.rfind("\n") + 1]
        _replace(path, text)
    rows = list(csv.DictReader(text.splitlines()))
    return [r for r in rows if r.get("spec_id")]


def _replace(path: Path, text: str) -> None:
    """Writes ``text`` to ``path`` atomically (a temporary file, then a rename): a crash leaves the
    old file or the new one, never neither."""
    tmp = path.with_name(path.name + ".tmp")
    with tmp.open("w", newline="", encoding="utf-8") as f:
        f.write(text)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def _widen(path: Path, have: list[dict[str, str]], columns: list[str]) -> bool:
    """Rewrites a records file written by an earlier version of the same study — its columns are
    the first ones of ``columns`` (a later version added fields at the end) — with the new header,
    the added fields empty, so a rerun resumes it. Atomic (a temporary file, then a rename);
    ``False`` (nothing written) if the columns differ otherwise."""
    old = list(have[0])
    if len(old) >= len(columns) or columns[: len(old)] != old:
        return False
    buf = io.StringIO(newline="")
    w = csv.DictWriter(buf, fieldnames=columns, restval="")
    w.writeheader()
    w.writerows(have)
    _replace(path, buf.getvalue())
    return True


def _client(client: Any, workers: int) -> tuple[Any, Callable[[], None]]:
    from dask.distributed import Client, LocalCluster

    if client is None:
        # One thread per worker, Rust's rayon pool included (CLOE would otherwise run its
        # stages ahead and speculative trials on every core in every worker).
        cluster = LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=":0",
            env={"RAYON_NUM_THREADS": "1"},
        )
        c = Client(cluster)

        def close() -> None:
            c.close()
            cluster.close()

        return c, close
    if isinstance(client, str):
        c = Client(client)
        return c, c.close
    return client, lambda: None


def run_study(
    task: Task,
    specs: Sequence[Mapping[str, Any]],
    *,
    out: str | Path,
    fields: Sequence[str],
    client: Any = None,
    workers: int = 2,
    retries: int = 2,
    progress: bool | Callable[[int, int], Any] = True,
) -> tuple[list[dict[str, str]], int]:
    """Maps ``task`` over the specs not yet in ``out`` and appends their records (columns
    ``fields`` + spec_id, status, error, seconds, worker_pid). Returns (every record in the file,
    the number of tasks this call ran). ``client``: a ``dask.distributed.Client``, a scheduler
    address, or None (a LocalCluster of ``workers`` processes). ``progress``: a tqdm bar (True) or
    ``progress(done, total)``. Ctrl-C cancels the rest; what finished is in the file."""
    from dask.distributed import as_completed

    ids = [str(s["spec_id"]) for s in specs]
    if len(set(ids)) != len(ids):
        raise InvalidInputError("spec_id must be unique within a study")
    columns = ["spec_id", "status", "error", "seconds", "worker_pid"]
    columns += [f for f in fields if f not in columns]
    path = Path(out)
    path.parent.mkdir(parents=True, exist_ok=True)
    have = read_records(path)
    if have and list(have[0]) != columns and not _widen(path, have, columns):
        raise InvalidInputError(
            f"{path} holds another study's records (columns {list(have[0])[:6]}…)"
        )
    done = {r["spec_id"] for r in have}
    todo = [s for s in specs if str(s["spec_id"]) not in done]
    if not todo:
        return have, 0
    c, close = _client(client, workers)
    bar = None
    if progress is True:
        from tqdm import tqdm

        bar = tqdm(total=len(todo), desc="study", leave=False)
    new = not path.exists() or path.stat().st_size == 0
    futures = []
    try:
        futures = c.map(
            _guarded,
            [task] * len(todo),
            todo,
            key=[f"rss6-study-{task.__name__}-{s['spec_id']}-{os.getpid()}" for s in todo],
            retries=retries,
            pure=False,
        )
        with path.open("a", newline="", encoding="utf-8") as f:
            w = csv.DictWriter(f, fieldnames=columns, extrasaction="ignore", restval="")
            if new:
                w.writeheader()
            for k, fut in enumerate(as_completed(futures), 1):
                try:
                    rec = fut.result()
                except Exception:  # e.g. KilledWorker after the retries: left for a rerun
                    continue
                if rec["spec_id"] in done:
                    continue
                done.add(rec["spec_id"])
                w.writerow(rec)
                f.flush()
                os.fsync(f.fileno())
                if bar is not None:
                    bar.update(1)
                elif callable(progress):
                    progress(k, len(todo))
    except KeyboardInterrupt:
        c.cancel(futures)
        raise
    finally:
        if bar is not None:
            bar.close()
        close()
    return read_records(path), len(todo)

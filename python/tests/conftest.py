"""Fixtures shared by the discrepancy tests (the model twin as the robot: ``twin_case``)."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import pytest
from rss6 import identify
from twin_case import KP


@pytest.fixture(scope="module")
def truth() -> tuple[Any, tuple[float, float, float]]:
    """Table 5.2's truth: (dynamics, drive gains)."""
    return identify.table_5_2_truth()


@pytest.fixture(scope="module")
def excitation() -> identify.Excitation:
    """The random excitation the discrepancy tests run (seed 1)."""
    return identify.random_excitation(KP, seed=1)


# The suite's order for pytest-xdist (CI runs `-n auto --dist worksteal`): worksteal hands each of
# the k workers an equal count of consecutive tests and lets an idle one take the second half of
# another's queue. In file order one worker's share held most of the slow discrepancy cases, and a
# slow case started late kept one core busy while the other idled. The tests measured slowest
# (`durations.json`: seconds with their setup, from one `-n auto --durations=0` run) are dealt out
# first, largest first, each to the worker with the least measured work, followed by the tests of
# its file that share a module fixture with it (set up once, not once per place); the rest follow
# in file order, where stealing evens out the end. Outside xdist the order is the files'.
DURATIONS = Path(__file__).with_name("durations.json")
SLOW_S = 5.0


def _module_fixtures(item: pytest.Item) -> set[str]:
    """The module-scoped fixtures ``item`` uses that its own file defines."""
    info = getattr(item, "_fixtureinfo", None)
    module = item.nodeid.split("::")[0]
    if info is None:
        return set()
    return {
        name
        for name, defs in info.name2fixturedefs.items()
        if any(d.scope == "module" and d.baseid == module for d in defs)
    }


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    k = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1"))
    if k < 2 or not DURATIONS.exists():
        return
    known: dict[str, float] = json.loads(DURATIONS.read_text())
    cost = [known.get(it.nodeid, 0.0) for it in items]
    fixtures = [_module_fixtures(it) for it in items]
    module = [it.nodeid.split("::")[0] for it in items]
    placed = [False] * len(items)
    # Worker w receives the consecutive block w of len(items) // k (the last one the remainder).
    sizes = [len(items) // k] * (k - 1) + [len(items) - (k - 1) * (len(items) // k)]
    blocks: list[list[int]] = [[] for _ in range(k)]
    sums = [0.0] * k
    for i in sorted(range(len(items)), key=lambda i: -cost[i]):
        if cost[i] < SLOW_S or placed[i]:
            continue
        group = [i] + [
            j
            for j in range(len(items))
            if j != i and not placed[j] and module[j] == module[i] and fixtures[i] & fixtures[j]
        ]
        room = [w for w in range(k) if len(blocks[w]) + len(group) <= sizes[w]]
        if not room:
            break
        w = min(room, key=lambda w: sums[w])
        for j in group:
            blocks[w].append(j)
            sums[w] += cost[j]
            placed[j] = True
    rest = [i for i in range(len(items)) if not placed[i]]
    for w in range(k):
        take = sizes[w] - len(blocks[w])
        blocks[w].extend(rest[:take])
        del rest[:take]
    items[:] = [items[i] for b in blocks for i in b]

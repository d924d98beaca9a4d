"""Oracle for mcl-plan's tests and benchmark: pyperplan's grounding,
heuristics and searches on PDDL files, one JSON line per instance.

    python3 pyperplan_oracle.py h DOMAIN PROBLEM [DOMAIN PROBLEM ...]
        -> {"hadd": H, "hmax": H}   (h_add and h_max of the initial state; null = infinite)
    python3 pyperplan_oracle.py solve SEARCH HEURISTIC DOMAIN PROBLEM [...]
        -> {"cost": N, "plan": [...], "seconds": T}
           SEARCH: bfs | astar | gbf ...; HEURISTIC: hadd | hmax | blind | none.
           seconds = parse + ground + search (no interpreter start-up); cost = plan
           length (pyperplan has unit costs), null without a plan.
"""
import json
import logging
import math
import sys
import time

from pyperplan.planner import HEURISTICS, SEARCHES, _ground, _parse
from pyperplan.search import searchspace

logging.disable(logging.CRITICAL)


def h_values(domain, problem):
    task = _ground(_parse(domain, problem))
    root = searchspace.make_root_node(task.initial_state)
    out = {}
    for name in ("hadd", "hmax"):
        v = HEURISTICS[name](task)(root)
        out[name] = None if v == math.inf else int(v)
    return out


def solve(search, heuristic, domain, problem):
    t = time.perf_counter()
    task = _ground(_parse(domain, problem))
    if heuristic == "none" or search in ("bfs", "ids", "sat"):
        plan = SEARCHES[search](task)
    else:
        plan = SEARCHES[search](task, HEURISTICS[heuristic](task))
    secs = time.perf_counter() - t
    return {
        "cost": None if plan is None else len(plan),
        "plan": None if plan is None else [op.name for op in plan],
        "seconds": secs,
    }


def main(argv):
    if len(argv) >= 3 and argv[0] == "h":
        files = argv[1:]
        for i in range(0, len(files) - 1, 2):
            print(json.dumps(h_values(files[i], files[i + 1])), flush=True)
    elif len(argv) >= 5 and argv[0] == "solve":
        search, heur, files = argv[1], argv[2], argv[3:]
        for i in range(0, len(files) - 1, 2):
            print(json.dumps(solve(search, heur, files[i], files[i + 1])), flush=True)
    else:
        print(__doc__, file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

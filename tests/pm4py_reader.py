"""Reads a PNML file with pm4py (an independent, widely used reader) and
prints what it found as JSON: places, transitions, arcs, initial marking."""
import json
import sys

import pm4py

net, initial, _final = pm4py.read_pnml(sys.argv[1])
print(json.dumps({
    "places": sorted(p.name for p in net.places),
    "transitions": sorted(t.name for t in net.transitions),
    "arcs": sorted([a.source.name, a.target.name, a.weight] for a in net.arcs),
    "initial": {p.name: n for p, n in initial.items()},
}))

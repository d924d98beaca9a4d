#!/usr/bin/env bash
# The monitor's cost on the player and its update latency (docs/monitor.md).
#
# 1. Firings per second of the real-time player (`mcl run --mock --speed
#    100000`: the mock answers at once, so the run is as fast as the player,
#    its link and its sinks) on a generated mission of 1,000 calls (9,001
#    firings), in three cases: without --monitor; with --monitor and no
#    page; with --monitor and the page open in headless Chromium. Each run
#    starts paused by the operator (--operator-token; so that the page is
#    connected before the first firing is timed), then is resumed; the time
#    is from the resume to the end of the process (B). A run without the
#    monitor cannot be paused: it is compared with a run with the monitor
#    and no page by the process's wall time less the time the same command
#    takes to compile the mission and end at once (`--time-limit 0`) (A).
# 2. Update latency: from the moment the run pushes a record to the moment
#    a client of the event stream (/api/events, Python on the same machine)
#    receives it (the `pushed_ms` of each message), over a run of
#    examples/survey.mcl at --speed 5 followed from its first firing.
#
# Usage: benches-scripts/monitor-bench.sh
#   Environment: RUNS (runs per case, default 5), MCL (a built binary to
#   time instead of building target/release/mcl), CHROMIUM (default chromium).
# Needs python3; the page case needs Chromium (skipped without it).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
RUNS="${RUNS:-5}"
CHROMIUM="${CHROMIUM:-chromium}"
if [ -z "${MCL:-}" ]; then
  cargo build --release --quiet --bin mcl
  MCL="$ROOT/target/release/mcl"
fi
TMP="$(mktemp -d "${TMPDIR:-/tmp}/mcl-monitor-bench.XXXXXX")"
trap 'rm -rf "$TMP"' EXIT

python3 - "$MCL" "$ROOT" "$TMP" "$RUNS" "$CHROMIUM" <<'PY'
import json, os, shutil, statistics, subprocess, sys, time, urllib.request

mcl, root, tmp, runs, chromium = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), sys.argv[5]
calls = " ;\n    ".join("Surface()" if i % 2 else "StopVehicle()" for i in range(1000))
big = os.path.join(tmp, "big.mcl")
open(big, "w").write(f'import "{root}/examples/vehicle.mcl";\n\nmission {{\n    {calls}\n}}\n')
fast = os.path.join(tmp, "fast.toml")
open(fast, "w").write("default_duration = 0\nseed = 1\n")
TOKEN = "bench"

def start(args):
    p = subprocess.Popen([mcl, *args], cwd=root, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    while True:
        line = p.stderr.readline()
        if not line:
            raise SystemExit("mcl printed no monitor URL")
        if line.startswith("monitor: "):
            return p, line.split()[1]

def post(url, body):
    req = urllib.request.Request(url + "api/operator", data=json.dumps(body).encode(),
                                 headers={"Authorization": "Bearer " + TOKEN}, method="POST")
    urllib.request.urlopen(req).read()

def firings(stderr):
    for line in stderr.splitlines():
        if "firings)" in line:
            return int(line.rsplit("events, ", 1)[1].split()[0])
    raise SystemExit("no summary line:\n" + stderr)

def timed_run(page):
    """Seconds from resume to the end, and the firings."""
    p, url = start(["run", "--mock", big, "--scenario", fast, "--speed", "100000", "-q",
                    "--monitor=127.0.0.1:0", "--operator-token", TOKEN])
    post(url, {"command": "pause"})
    # The driver has taken the pause (the run is set up and its loop runs).
    while not json.load(urllib.request.urlopen(url + "api/state"))["paused"]:
        time.sleep(0.01)
    browser = None
    if page:
        prof = os.path.join(tmp, "chromium")
        shutil.rmtree(prof, ignore_errors=True)
        browser = subprocess.Popen([chromium, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                                    f"--user-data-dir={prof}", "--remote-debugging-port=0", url],
                                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(4)  # the page, if any, loads and opens its event stream
    t0 = time.perf_counter()
    post(url, {"command": "resume"})
    rest = p.stderr.read()
    p.wait()
    t1 = time.perf_counter()
    if browser:
        browser.kill()
        browser.wait()
    return t1 - t0, firings(rest)

def plain_run(extra):
    t0 = time.perf_counter()
    out = subprocess.run([mcl, "run", "--mock", big, "--scenario", fast, "--speed", "100000", "-q", *extra],
                         cwd=root, capture_output=True, text=True)
    return time.perf_counter() - t0, out.stderr

def report(title, cases):
    print(title)
    for name, wall, n in cases:
        print(f"  {name:34s} {n} firings in {wall * 1e3:7.1f} ms: {n / wall:9.0f} firings/s")

# A: the whole process, less the same command ended at once (--time-limit 0).
cases = []
for name, extra in (("no monitor", []), ("--monitor, no page", ["--monitor=127.0.0.1:0"])):
    base = statistics.median(plain_run(extra + ["--time-limit", "0"])[0] for _ in range(runs))
    walls, n = [], 0
    for _ in range(runs):
        w, err = plain_run(extra)
        walls.append(w - base)
        n = firings(err)
    cases.append((name, statistics.median(walls), n))
report(f"A. process wall time less start-up, {runs} runs per case (median):", cases)
# B: from the operator's resume to the end of the process.
cases = []
for name, page in (("--monitor, no page", False), ("--monitor, page open in Chromium", True)):
    if page and shutil.which(chromium) is None:
        print(f"skipped: {name} ({chromium} not found)")
        continue
    res = [timed_run(page) for _ in range(runs)]
    cases.append((name, statistics.median(w for w, _ in res), res[0][1]))
report(f"B. from the operator's resume to the end, {runs} runs per case (median):", cases)

# Latency: a client of the event stream follows the survey from its first firing.
p, url = start(["run", "--mock", "examples/survey.mcl", "--speed", "5", "-q", "--monitor=127.0.0.1:0",
                "--operator-token", TOKEN])
post(url, {"command": "pause"})
stream = urllib.request.urlopen(url + "api/events?from=0")
lat, event = [], None
post(url, {"command": "resume"})
for raw in stream:
    line = raw.decode().rstrip("\n")
    if line.startswith("event: "):
        event = line[7:]
    elif line.startswith("data: ") and event == "records":
        msg = json.loads(line[6:])
        if msg["from"] > 0 and msg["pushed_ms"] is not None:
            lat.append(time.time() * 1e3 - msg["pushed_ms"])
    elif line.startswith("data: ") and event == "status":
        break
p.wait()
lat.sort()
print(f"update latency over {len(lat)} messages: median {statistics.median(lat):.2f} ms, "
      f"p90 {lat[int(0.9 * (len(lat) - 1))]:.2f} ms, max {lat[-1]:.2f} ms")
PY

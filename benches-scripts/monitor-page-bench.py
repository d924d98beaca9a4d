#!/usr/bin/env python3
"""The monitor page's drawing cost in a real headless Chromium (BENCHMARKS.md,
"mcl-monitor"), driven over the Chrome DevTools protocol.

A generated mission of 1,000 sequential calls (9,001 firings, 12,002
records; the mock answers at once):

1. Replay (`mcl monitor TRACE`): the page's `seek` and `render` timed in the
   page with `performance.now()`, a forced layout included (`render()` then
   reading `document.body.offsetHeight`): the whole run at once, then 50
   steps forward through the run, then 50 steps backward (each a redraw from
   scratch). `Performance.getMetrics` gives the layout and style time of
   the whole sequence.
2. Live (`mcl run --mock --speed S --monitor`, each call 1 s of mission
   time: at the default S = 200, 1,000 s of mission in about 5 s, some
   2,400 records a second): the page follows the run
   from its first firing (the run starts paused by the operator and is
   resumed once the page is connected); the page's own `mclRenderMs` (every
   redraw's duration, one per animation frame at most) is read at the end.
   Pages without `mclRenderMs` (an older binary) report the replay only.

Usage: benches-scripts/monitor-page-bench.py [MCL ...]
  Each MCL is a built binary (default target/release/mcl, else
  target/debug/mcl); several compare their pages on the same machine.
  Environment: CHROMIUM (default chromium), SPEED (live run, default 200).
Standard library only (a minimal WebSocket client below).
"""

import base64
import json
import os
import shutil
import socket
import statistics
import struct
import subprocess
import sys
import tempfile
import time
import urllib.request

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CHROMIUM = os.environ.get("CHROMIUM", "chromium")
SPEED = os.environ.get("SPEED", "200")
TOKEN = "bench"


class WebSocket:
    """A client of RFC 6455 text frames, enough for the DevTools protocol."""

    def __init__(self, url):
        assert url.startswith("ws://"), url
        hostport, _, path = url[5:].partition("/")
        host, _, port = hostport.partition(":")
        self.sock = socket.create_connection((host, int(port)))
        key = base64.b64encode(os.urandom(16)).decode()
        self.sock.sendall(
            (f"GET /{path} HTTP/1.1\r\nHost: {hostport}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
             f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n").encode())
        head = b""
        while b"\r\n\r\n" not in head:
            chunk = self.sock.recv(1)
            if not chunk:
                raise SystemExit("the DevTools socket closed during the handshake")
            head += chunk
        if b" 101 " not in head.split(b"\r\n", 1)[0]:
            raise SystemExit(f"no WebSocket upgrade: {head!r}")

    def _exact(self, n):
        out = b""
        while len(out) < n:
            chunk = self.sock.recv(n - len(out))
            if not chunk:
                raise SystemExit("the DevTools socket closed")
            out += chunk
        return out

    def send(self, text):
        data = text.encode()
        n = len(data)
        if n < 126:
            head = struct.pack("!BB", 0x81, 0x80 | n)
        elif n < 1 << 16:
            head = struct.pack("!BBH", 0x81, 0x80 | 126, n)
        else:
            head = struct.pack("!BBQ", 0x81, 0x80 | 127, n)
        mask = os.urandom(4)
        self.sock.sendall(head + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(data)))

    def recv(self):
        parts = []
        while True:
            b0, b1 = self._exact(2)
            n = b1 & 0x7F
            if n == 126:
                n = struct.unpack("!H", self._exact(2))[0]
            elif n == 127:
                n = struct.unpack("!Q", self._exact(8))[0]
            payload = self._exact(n)
            opcode = b0 & 0x0F
            if opcode == 8:
                raise SystemExit("the DevTools socket closed")
            if opcode == 9:  # ping
                continue
            parts.append(payload)
            if b0 & 0x80:
                return b"".join(parts).decode()


class Page:
    """One page of a headless Chromium."""

    def __init__(self, profile):
        self.proc = subprocess.Popen(
            [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
             "--disable-background-networking", "--remote-debugging-port=0", "--remote-allow-origins=*",
             "--window-size=1400,1000", f"--user-data-dir={profile}", "about:blank"],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        port_file = os.path.join(profile, "DevToolsActivePort")
        for _ in range(600):
            if os.path.exists(port_file) and open(port_file).read().count("\n") >= 1:
                break
            time.sleep(0.05)
        port = open(port_file).read().split("\n")[0]
        targets = json.load(urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list"))
        page = next(t for t in targets if t["type"] == "page")
        self.ws = WebSocket(page["webSocketDebuggerUrl"])
        self.next_id = 0
        self.call("Runtime.enable")
        self.call("Page.enable")
        self.call("Performance.enable")

    def call(self, method, params=None):
        self.next_id += 1
        self.ws.send(json.dumps({"id": self.next_id, "method": method, "params": params or {}}))
        while True:
            msg = json.loads(self.ws.recv())
            if msg.get("id") == self.next_id:
                if "error" in msg:
                    raise SystemExit(f"{method}: {msg['error']}")
                return msg.get("result", {})

    def eval(self, expr):
        r = self.call("Runtime.evaluate", {"expression": expr, "returnByValue": True, "awaitPromise": True})
        if "exceptionDetails" in r:
            raise SystemExit(f"{expr[:80]}...: {r['exceptionDetails']}")
        return r["result"].get("value")

    def wait(self, expr, what, limit=120):
        deadline = time.time() + limit
        while not self.eval(expr):
            if time.time() > deadline:
                raise SystemExit(f"waited {limit} s for {what}")
            time.sleep(0.05)

    def metrics(self):
        return {m["name"]: m["value"] for m in self.call("Performance.getMetrics")["metrics"]}

    def close(self):
        self.proc.kill()
        self.proc.wait()


def start(mcl, args):
    p = subprocess.Popen([mcl, *args], cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
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


def ms(xs):
    xs = sorted(xs)
    return f"median {statistics.median(xs):6.1f} ms, p90 {xs[int(0.9 * (len(xs) - 1))]:6.1f} ms, max {xs[-1]:6.1f} ms"


# Timed in the page: `seek` and `render`, then a forced layout.
STEPS = """(() => {
  const tmax = records[records.length - 1].t;
  const timed = (t) => { const t0 = performance.now(); seek(t); render(); void document.body.offsetHeight; return performance.now() - t0; };
  timed(0);
  const whole = timed(tmax);
  timed(0);
  const forward = [];
  for (let k = 1; k <= 50; k++) forward.push(timed((tmax * k) / 50));
  const backward = [];
  for (let k = 49; k >= 0; k--) backward.push(timed((tmax * k) / 50));
  return { whole, forward, backward, records: records.length, calls: st.calls.size };
})()"""


def bench(mcl, tmp, big, fast, paced):
    print(f"== {mcl}")
    trace = os.path.join(tmp, "big.jsonl")
    subprocess.run([mcl, "run", "--mock", "--virtual-time", big, "--scenario", fast, "-q", "--trace", trace],
                   cwd=ROOT, check=True, capture_output=True)
    server, url = start(mcl, ["monitor", trace, "--listen", "127.0.0.1:0"])
    profile = os.path.join(tmp, "chromium")
    shutil.rmtree(profile, ignore_errors=True)
    page = Page(profile)
    try:
        page.call("Page.navigate", {"url": url})
        page.wait("document.body && document.body.dataset.ready === '1' && records.length > 0", "the replay")
        before = page.metrics()
        r = page.eval(STEPS)
        after = page.metrics()
        print(f"replay of {r['records']} records, {r['calls']} calls (seek + render + layout):")
        print(f"  the whole run at once: {r['whole']:.1f} ms")
        print(f"  50 steps forward:  {ms(r['forward'])}")
        print(f"  50 steps backward: {ms(r['backward'])} (each from scratch)")
        d = {k: (after.get(k, 0) - before.get(k, 0)) * 1e3 for k in ("ScriptDuration", "LayoutDuration", "RecalcStyleDuration", "TaskDuration")}
        print("  Performance.getMetrics over the 102 redraws: " + ", ".join(f"{k} {v:.0f} ms" for k, v in d.items()))
    finally:
        page.close()
        server.kill()
        server.wait()

    # Live: the page follows the run from its first firing.
    run, url = start(mcl, ["run", "--mock", big, "--scenario", paced, "--speed", SPEED, "-q",
                           "--monitor=127.0.0.1:0", "--monitor-linger", "inf", "--operator-token", TOKEN])
    shutil.rmtree(profile, ignore_errors=True)
    page = Page(profile)
    try:
        post(url, {"command": "pause"})
        page.call("Page.navigate", {"url": url})
        page.wait("document.body && document.body.dataset.ready === '1'", "the live page")
        if not page.eval("Array.isArray(window.mclRenderMs)"):
            # An older page: its `render` is wrapped to time it the same way.
            page.eval("window.mclRenderMs = []; { const f = render; render = function () {"
                      " const t0 = performance.now(); f(); window.mclRenderMs.push(performance.now() - t0); }; } true")
            print("  (an older page: its render() wrapped to time it)")
        before = page.metrics()
        t0 = time.time()
        post(url, {"command": "resume"})
        page.wait("finished && Number(document.body.dataset.rendered) === records.length", "the end of the run", 600)
        wall = time.time() - t0
        after = page.metrics()
        r = page.eval("({ ms: window.mclRenderMs, records: records.length, latency: window.mclLatencyMs })")
        print(f"live at --speed {SPEED}: {r['records']} records followed in {wall:.1f} s, {len(r['ms'])} redraws: {ms(r['ms'])}")
        top = sorted(range(len(r["ms"])), key=lambda i: -r["ms"][i])[:3]
        print("  the longest redraws (their rank in the run): " + ", ".join(f"#{i + 1} {r['ms'][i]:.1f} ms" for i in top))
        d = {k: (after.get(k, 0) - before.get(k, 0)) * 1e3 for k in ("ScriptDuration", "LayoutDuration", "RecalcStyleDuration", "TaskDuration")}
        print("  Performance.getMetrics over the run: " + ", ".join(f"{k} {v:.0f} ms" for k, v in d.items()))
    finally:
        page.close()
        run.kill()
        run.wait()


def main():
    mcls = sys.argv[1:]
    if not mcls:
        rel = os.path.join(ROOT, "target/release/mcl")
        mcls = [rel if os.path.exists(rel) else os.path.join(ROOT, "target/debug/mcl")]
    if shutil.which(CHROMIUM) is None:
        raise SystemExit(f"{CHROMIUM} not found (set CHROMIUM)")
    tmp = tempfile.mkdtemp(prefix="mcl-monitor-page-bench.")
    try:
        calls = " ;\n    ".join("Surface()" if i % 2 else "StopVehicle()" for i in range(1000))
        big = os.path.join(tmp, "big.mcl")
        open(big, "w").write(f'import "{ROOT}/examples/vehicle.mcl";\n\nmission {{\n    {calls}\n}}\n')
        fast = os.path.join(tmp, "fast.toml")
        open(fast, "w").write("default_duration = 0\nseed = 1\n")
        paced = os.path.join(tmp, "paced.toml")
        open(paced, "w").write("default_duration = 1\nseed = 1\n")
        for mcl in mcls:
            bench(os.path.abspath(mcl), tmp, big, fast, paced)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()

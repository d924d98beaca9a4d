#!/usr/bin/env python3
"""A minimal AAC (vehicle side of the MCL player protocol, version 1).

Written from docs/aac-protocol.md alone (no other AAC implementation was
read), as a check that the document suffices. Standard library only.

    python3 aac.py HOST:PORT [--delay SECONDS] [--token T]

Nominal vehicle: every primitive enabled (a command other than `disable`)
answers after --delay with the `ok` event of the action's `task` taken from
the hello's `events` (role "ok", §3, §11), carrying `activation` = the seq
of the action that started that run (§6). Never answered (§11): an action
whose task has no ok event there, a call listed with role "condition" (a
monitor's condition: answering it would raise the alarm), a run disabled
meanwhile, and a run whose params say `"mode": "keep"` (the keep mode of
examples/vehicle.mcl, §11). Prints `listening on ADDR` first, then logs
every message on stderr.
"""

import hmac
import json
import socket
import sys
import threading
import uuid

LINE_LIMIT = 65536          # §1
TIMEOUT = 5.0               # §7: silent peer (and no hello) gone after 5 s
KEEP = 100_000              # §6: bound on the outbox

lock = threading.RLock()    # guards every session and every send
sessions = {}               # (mission, run) -> Session


def log(*a):
    print(*a, file=sys.stderr, flush=True)


def is_int(v):
    return isinstance(v, int) and not isinstance(v, bool) and v >= 0  # §1


class Session:
    def __init__(self):
        self.id = uuid.uuid4().hex[:12]
        self.last_seq = 0
        self.n = 0              # last event number given
        self.outbox = []        # [(n, message)] not yet confirmed
        self.conn = None        # the Conn carrying it now
        self.ok_event = {}      # task -> its ok event (from hello.events)
        self.watched = {}       # task -> call sites that are a monitor's condition
        self.running = {}       # primitive -> activation (seq) of its current run

    def emit(self, msg):        # number, keep and send an event (under lock)
        self.n += 1
        msg["n"] = self.n
        self.outbox.append((self.n, msg))
        del self.outbox[:-KEEP]
        if self.conn:
            self.conn.send(msg)

    def confirm(self, last_event):
        self.outbox = [(n, m) for n, m in self.outbox if n > last_event]


class Conn:
    def __init__(self, sock):
        self.sock = sock
        self.session = None
        self.closed = False

    def send(self, msg):
        if self.closed:
            return
        line = json.dumps(msg, separators=(",", ":")) + "\n"
        log("<", line.rstrip())
        try:
            self.sock.sendall(line.encode())
        except OSError:
            self.closed = True

    def error(self, code, message, seq=None, fatal=False):
        msg = {"type": "error", "code": code, "message": message}
        if seq is not None:
            msg["seq"] = seq
        self.send(msg)
        if fatal:
            self.close()

    def close(self):
        self.closed = True
        try:
            self.sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        self.sock.close()

    def lines(self):            # §1: JSON lines, 64 KiB limit, \r ignored
        buf = b""
        while not self.closed:
            try:
                chunk = self.sock.recv(65536)
            except socket.timeout:
                self.error("timeout", "nothing received for %g s" % TIMEOUT, fatal=True)
                return
            except OSError:
                return
            if not chunk:
                return
            buf += chunk
            while b"\n" in buf:
                line, buf = buf.split(b"\n", 1)
                yield line
            if len(buf) > LINE_LIMIT:   # read the long line to its end, discard it
                size = len(buf)
                while b"\n" not in buf:
                    more = self.sock.recv(65536)
                    if not more:
                        return
                    size += len(more)
                    buf = more
                size += buf.index(b"\n") - len(buf)
                buf = buf.split(b"\n", 1)[1]
                self.error("too_long", "line of %d bytes exceeds the limit of %d bytes; discarded"
                           % (size, LINE_LIMIT))

    def serve(self):
        self.sock.settimeout(TIMEOUT)
        try:
            for raw in self.lines():
                if raw.endswith(b"\r"):
                    raw = raw[:-1]
                if len(raw) > LINE_LIMIT:
                    self.error("too_long", "line of %d bytes exceeds the limit" % len(raw))
                    continue
                log(">", raw.decode("utf-8", "replace"))
                try:
                    msg = json.loads(raw.decode("utf-8"))
                except (ValueError, UnicodeDecodeError) as e:
                    self.error("malformed", "invalid JSON: %s" % e)
                    continue
                if not isinstance(msg, dict) or not isinstance(msg.get("type"), str):
                    self.error("malformed", "not an object with a string `type`")
                    continue
                with lock:
                    self.handle(msg)
        finally:
            with lock:
                if self.session and self.session.conn is self:
                    self.session.conn = None
            if not self.closed:
                self.close()

    def handle(self, msg):
        t = msg["type"]
        if t not in ("hello", "action", "ping", "pong", "error", "welcome", "ack",
                     "event", "perception"):
            self.error("unknown_type", "unknown message type `%s`" % t)
        elif t == "error":
            log("player error:", msg)   # never answered (§8)
        elif t == "pong":
            pass
        elif t == "ping":
            if self.session and is_int(msg.get("last_event")):
                self.session.confirm(msg["last_event"])
            self.send({"type": "pong"})
        elif t == "hello":
            self.hello(msg)
        elif t == "action":
            self.action(msg)
        else:
            self.error("unexpected", "`%s` is not sent to an AAC" % t)

    def hello(self, msg):
        if self.session:
            return self.error("unexpected", "a second hello")
        if not is_int(msg.get("version")):
            return self.error("malformed", "bad `hello` message: `version` must be an integer")
        if msg["version"] != 1:
            return self.error("version", "this AAC speaks protocol version 1, not %s"
                              % msg["version"], fatal=True)
        if TOKEN is not None and not hmac.compare_digest(
                str(msg.get("token") or "").encode(), TOKEN.encode()):
            return self.error("unauthorized", "this AAC requires a token", fatal=True)
        # §2: no `run`, nothing to resume: a session of its own.
        key = (msg.get("mission") or "mission", msg.get("run") or uuid.uuid4().hex)
        s = sessions.get(key)
        if s is None:
            s = sessions[key] = Session()
        if s.conn and s.conn is not self:      # §2: take the session over
            s.conn.error("replaced", "another connection took over this session", fatal=True)
        s.conn = self
        self.session = s
        for e in msg.get("events") or []:
            if not isinstance(e, dict) or not isinstance(e.get("task"), str):
                continue
            if e.get("role") == "ok":
                s.ok_event.setdefault(e["task"], e["event"])
            elif e.get("role") == "condition":
                s.watched.setdefault(e["task"], set()).update(e.get("call_sites") or [])
        self.send({"type": "welcome", "version": 1, "last_seq": s.last_seq,
                   "last_event": s.n, "session": s.id, "aac": "stranger-aac/0.1"})
        if is_int(msg.get("last_event")):       # §4 step 4, §6
            above = msg["last_event"] if msg.get("session") == s.id else 0
            for n, m in s.outbox:
                if n > above:
                    self.send(m)

    def action(self, msg):
        s = self.session
        seq = msg.get("seq")
        if s is None:
            return self.error("unexpected", "action before hello",
                              seq if is_int(seq) else None)
        for field in ("seq", "action", "primitive", "command"):
            ok = is_int(seq) and seq >= 1 if field == "seq" else isinstance(msg.get(field), str)
            if not ok:
                return self.error("malformed", "bad `action` message: missing or mistyped `%s`"
                                  % field, seq if is_int(seq) else None)
        if seq > s.last_seq:                    # §5: execute each seq once
            s.last_seq = seq
            params = msg.get("params") if isinstance(msg.get("params"), dict) else {}
            self.execute(s, seq, msg["primitive"], msg["command"], params,
                         msg.get("task"), msg.get("call_site"))
        self.send({"type": "ack", "seq": seq})

    def execute(self, s, seq, primitive, command, params, task, call_site):
        if command == "disable":
            s.running.pop(primitive, None)      # never answer that run (§6, §11)
            return
        if primitive in s.running:              # a reconfiguration of the same run
            return
        s.running[primitive] = seq
        event = s.ok_event.get(task)
        if event is None or call_site in s.watched.get(task, ()) or params.get("mode") == "keep":
            return                              # no ok end, condition, keep mode: silent

        def answer():
            with lock:
                if s.running.get(primitive) == seq:
                    s.emit({"type": "event", "event": event, "activation": seq})
        t = threading.Timer(DELAY, answer)
        t.daemon = True
        t.start()


def main(argv):
    global DELAY, TOKEN
    DELAY, TOKEN = 0.05, None
    args = list(argv)
    addr = "127.0.0.1:7010"
    while args:
        a = args.pop(0)
        if a == "--delay":
            DELAY = float(args.pop(0))
        elif a == "--token":
            TOKEN = args.pop(0)
        else:
            addr = a
    host, port = addr.rsplit(":", 1)
    srv = socket.socket()
    srv.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    srv.bind((host, int(port)))
    srv.listen()
    print("listening on %s:%d" % srv.getsockname()[:2], flush=True)
    while True:
        sock, _ = srv.accept()
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        threading.Thread(target=Conn(sock).serve, daemon=True).start()


if __name__ == "__main__":
    main(sys.argv[1:])

#!/usr/bin/env python3
"""Reference AAC (vehicle side) of the MCL AAC protocol, version 1.

Standard library only (Python 3.8+). The protocol is specified in
docs/aac-protocol.md: JSON lines over TCP; the MCL player connects, sends
``hello``, then ``action`` messages; the AAC acknowledges each action and
sends ``event`` and ``perception`` messages.

Use it as a library::

    from mcl_aac import AacServer

    def on_action(server, action):
        # action: dict with seq, action, primitive, command, params, task, call_site
        if action["command"] == "enable" and action["primitive"] == "GotoPrimitive":
            # activation: the seq of the action that started this run of the
            # primitive, so that the player can drop an answer that crossed
            # a `disable` on the wire (docs/aac-protocol.md, section 6).
            start_goto(action["params"]["way-point"],
                       done=lambda: server.send_event("eventGotoOk", activation=action["seq"]))

    server = AacServer(host="127.0.0.1", port=7010, token="s3cret", on_action=on_action)
    server.serve_forever()

What this class does for you: the handshake (version and token checks),
the line size limit, malformed input (error replies, never a crash),
heartbeats (pong, and dropping a silent player), executing each action
``seq`` once per session (a re-sent action is acknowledged, not executed
again), numbering events and re-sending them to a player that reconnects.
``on_action`` is called once per action, in order, from the connection's
thread; it must return quickly (start the primitive, don't wait for it).
Events and perceptions may be sent from any thread at any time.

Run it as a program for a trivial vehicle (see ``--help``): every ``enable``
ends ok after ``--delay`` seconds by sending the event mapped to its
primitive (``--map GotoPrimitive=eventGotoOk``, ``--map-file map.json``),
by default ``eventXyzOk`` for ``XyzPrimitive``; a ``disable`` before then
cancels the answer.
"""

import argparse
import json
import os
import socket
import sys
import threading
import time
import traceback

PROTOCOL_VERSION = 1
MAX_LINE = 64 * 1024
DEFAULT_ADDR = "127.0.0.1:7010"
DEFAULT_TIMEOUT = 5.0
MAX_OUTBOX = 100000  # events and perceptions kept per session until a player confirms them
MESSAGE_TYPES = ("hello", "welcome", "action", "ping", "ack", "event", "perception", "pong", "error")


def _log_stderr(msg):
    sys.stderr.write("mcl_aac: %s\n" % msg)
    sys.stderr.flush()


class ProtocolError(Exception):
    """A line that is not a valid message: what to put in the error reply."""

    def __init__(self, code, message, seq=None):
        Exception.__init__(self, message)
        self.code = code
        self.message = message
        self.seq = seq


def _is_int(v):
    """A JSON integer (bool is a subclass of int in Python: not one)."""
    return isinstance(v, int) and not isinstance(v, bool)


def parse_line(line):
    """Parses one line (bytes, without its newline) into a dict, or raises ProtocolError."""
    try:
        msg = json.loads(line.decode("utf-8"))
    except (UnicodeDecodeError, ValueError) as e:
        raise ProtocolError("malformed", "invalid JSON: %s" % e)
    if not isinstance(msg, dict):
        raise ProtocolError("malformed", "a message must be a JSON object")
    seq = msg.get("seq") if _is_int(msg.get("seq")) else None
    ty = msg.get("type")
    if not isinstance(ty, str):
        raise ProtocolError("malformed", "missing or non-string field `type`", seq)
    if ty not in MESSAGE_TYPES:
        raise ProtocolError("unknown_type", "unknown message type `%s`" % ty[:64], seq)
    if ty == "action":
        if seq is None or seq < 0:
            raise ProtocolError("malformed", "bad `action` message: `seq` must be a non-negative integer")
        for field in ("action", "primitive", "command"):
            if not isinstance(msg.get(field), str):
                raise ProtocolError("malformed", "bad `action` message: missing string field `%s`" % field, seq)
        params = msg.get("params", {})
        if params is None:
            params = {}
        if not isinstance(params, dict):
            raise ProtocolError("malformed", "bad `action` message: `params` must be an object", seq)
        msg["params"] = params
        msg.setdefault("task", None)
        msg.setdefault("call_site", None)
    elif ty == "hello":
        if not _is_int(msg.get("version")) or msg["version"] < 0:
            raise ProtocolError("malformed", "bad `hello` message: missing integer field `version`")
        for field in ("last_event",):
            if msg.get(field) is not None and (not _is_int(msg[field]) or msg[field] < 0):
                raise ProtocolError("malformed", "bad `hello` message: `%s` must be a non-negative integer" % field)
        for field in ("token", "player", "mission", "run", "session"):
            if msg.get(field) is not None and not isinstance(msg[field], str):
                raise ProtocolError("malformed", "bad `hello` message: `%s` must be a string" % field)
    elif ty == "ping":
        last = msg.get("last_event")
        if last is not None and (not _is_int(last) or last < 0):
            raise ProtocolError("malformed", "bad `ping` message: `last_event` must be a non-negative integer")
    return msg


def encode(msg):
    """One message as one line (bytes, newline included)."""
    return (json.dumps(msg, separators=(",", ":"), ensure_ascii=False) + "\n").encode("utf-8")


class _Session(object):
    """One run of one mission, whatever connections carry it."""

    def __init__(self, mission, run):
        self.mission = mission
        self.run = run
        self.id = "%x-%x-%s" % (int(time.time() * 1e6), os.getpid(), os.urandom(3).hex())
        self.last_seq = 0
        self.last_event = 0
        # [(n, line bytes)] sent or to send, not yet confirmed by the player
        # (its ping's or hello's `last_event`): re-sent after a reconnection
        # or a restart of the player (docs/aac-protocol.md, section 6).
        self.outbox = []
        self.conn = None


class _Connection(object):
    def __init__(self, sock, peer):
        self.sock = sock
        self.peer = peer
        self.lock = threading.Lock()
        self.closed = False

    def send(self, msg_or_line):
        data = msg_or_line if isinstance(msg_or_line, bytes) else encode(msg_or_line)
        with self.lock:
            if self.closed:
                return False
            try:
                self.sock.sendall(data)
                return True
            except OSError:
                self.closed = True
                return False

    def close(self):
        with self.lock:
            self.closed = True
        try:
            self.sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass


class AacServer(object):
    """An AAC server: see the module documentation."""

    def __init__(self, host="127.0.0.1", port=7010, token=None, on_action=None, timeout=DEFAULT_TIMEOUT,
                 max_line=MAX_LINE, log=_log_stderr, verbose=False, name="mcl_aac.py/1", max_outbox=MAX_OUTBOX):
        self.token = token
        self.max_outbox = max_outbox
        self.on_action = on_action
        self.timeout = timeout
        self.max_line = max_line
        self.log = log or (lambda msg: None)
        self.verbose = verbose
        self.name = name
        self._lock = threading.RLock()
        self._sessions = {}
        self._current = None
        self._listener = socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET, socket.SOCK_STREAM)
        self._listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self._listener.bind((host, port))
        self._listener.listen(16)
        self._stopping = False

    @property
    def address(self):
        """(host, port) actually bound (useful with port 0)."""
        return self._listener.getsockname()[:2]

    # -- the vehicle side's API -------------------------------------------

    def send_event(self, name, session=None, activation=None):
        """Sends event `name` to the player of `session` (default: the latest session).

        `activation` is the `seq` of the action that started the primitive run
        raising the event: give it, so that the player ignores an answer of a
        run it has disabled meanwhile (it crossed the `disable` on the wire).
        """
        msg = {"type": "event", "event": name}
        if activation is not None:
            msg["activation"] = activation
        self._push(session, msg)

    def send_perception(self, name, value, session=None):
        """Sends perception `name` with a JSON value."""
        self._push(session, {"type": "perception", "name": name, "value": value})

    def serve_forever(self):
        """Accepts players until close(); one thread per connection."""
        self.log("listening on %s:%d" % self.address)
        while not self._stopping:
            try:
                sock, peer = self._listener.accept()
            except OSError:
                if self._stopping:
                    break
                time.sleep(0.1)
                continue
            t = threading.Thread(target=self._connection, args=(sock, "%s:%d" % peer[:2]), daemon=True)
            t.start()

    def start(self):
        """Runs serve_forever() in a daemon thread and returns the thread."""
        t = threading.Thread(target=self.serve_forever, daemon=True)
        t.start()
        return t

    def close(self):
        self._stopping = True
        try:
            self._listener.close()
        except OSError:
            pass

    # -- internals ----------------------------------------------------------

    def _push(self, session, msg):
        with self._lock:
            s = session or self._current
            if s is None:
                self.log("no session yet: dropped %s" % json.dumps(msg))
                return
            s.last_event += 1
            msg["n"] = s.last_event
            line = encode(msg)
            s.outbox.append((s.last_event, line))
            if len(s.outbox) > self.max_outbox:
                # Bounded: the oldest are forgotten (the player logs the gap).
                del s.outbox[:len(s.outbox) - self.max_outbox]
            conn = s.conn
        if conn is not None:
            if self.verbose:
                self.log("%s -> %s" % (conn.peer, line.decode("utf-8").rstrip()))
            conn.send(line)

    def _reply(self, conn, msg):
        line = encode(msg)
        if self.verbose:
            self.log("%s -> %s" % (conn.peer, line.decode("utf-8").rstrip()))
        conn.send(line)

    def _error(self, conn, code, message, seq=None):
        self.log("%s: %s: %s" % (conn.peer, code, message))
        msg = {"type": "error", "code": code, "message": message}
        if seq is not None:
            msg["seq"] = seq
        self._reply(conn, msg)

    def _lines(self, conn, f):
        """Yields lines (bytes) or ('too_long', n); stops at the end or on silence."""
        while True:
            try:
                line = f.readline(self.max_line + 1)
            except socket.timeout:
                self._error(conn, "timeout", "no message for %.1f s" % self.timeout)
                return
            except OSError:
                return
            if not line:
                return
            if not line.endswith(b"\n") and len(line) > self.max_line:
                # Too long: discard up to the end of the line.
                n = len(line)
                while True:
                    try:
                        more = f.readline(self.max_line + 1)
                    except (socket.timeout, OSError):
                        return
                    n += len(more)
                    if not more or more.endswith(b"\n"):
                        break
                yield ("too_long", n - 1)
                continue
            line = line.rstrip(b"\n")
            if line.endswith(b"\r"):
                line = line[:-1]
            if len(line) > self.max_line:
                yield ("too_long", len(line))
                continue
            yield line

    def _connection(self, sock, peer):
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        sock.settimeout(self.timeout)
        conn = _Connection(sock, peer)
        f = sock.makefile("rb")
        session = None
        self.log("%s connected" % peer)
        try:
            for line in self._lines(conn, f):
                if isinstance(line, tuple):
                    self._error(conn, "too_long", "line of %d bytes exceeds the limit of %d bytes; discarded"
                                % (line[1], self.max_line))
                    continue
                if self.verbose:
                    self.log("%s <- %s" % (peer, line[:300].decode("utf-8", "replace")))
                try:
                    msg = parse_line(line)
                except ProtocolError as e:
                    self._error(conn, e.code, e.message, e.seq)
                    continue
                ty = msg["type"]
                if session is None:
                    if ty == "hello":
                        session = self._hello(conn, msg)
                        if session is None:
                            return
                    elif ty == "error":
                        self.log("%s reports an error: %s" % (peer, msg))
                    else:
                        self._error(conn, "unexpected", "expected `hello` first, got `%s`" % ty, msg.get("seq"))
                    continue
                if session.conn is not conn:
                    self._error(conn, "replaced", "another connection took over this session")
                    return
                if ty == "action":
                    self._action(conn, session, msg)
                elif ty == "ping":
                    with self._lock:
                        last = msg.get("last_event")
                        if _is_int(last):
                            session.outbox = [(n, l) for (n, l) in session.outbox if n > last]
                    self._reply(conn, {"type": "pong"})
                elif ty == "pong":
                    pass
                elif ty == "error":
                    self.log("%s reports an error: %s" % (peer, msg))
                elif ty == "hello":
                    self._error(conn, "unexpected", "already in a session: `hello` is only the first message")
                else:
                    self._error(conn, "unexpected", "an AAC does not accept `%s`" % ty)
        finally:
            with self._lock:
                if session is not None and session.conn is conn:
                    session.conn = None
            conn.close()
            try:
                sock.close()
            except OSError:
                pass
            self.log("%s disconnected" % peer)

    def _hello(self, conn, msg):
        if msg["version"] != PROTOCOL_VERSION:
            self._error(conn, "version", "this AAC speaks protocol version %d, not %s"
                        % (PROTOCOL_VERSION, msg["version"]))
            return None
        if self.token is not None and msg.get("token") != self.token:
            self._error(conn, "unauthorized", "wrong token" if "token" in msg else "this AAC requires a token")
            return None
        # No `run`: nothing to resume, a session of its own (§2).
        key = (str(msg.get("mission") or ""), str(msg.get("run") or "unnamed-" + os.urandom(8).hex()))
        with self._lock:
            s = self._sessions.get(key)
            created = s is None
            if created:
                s = _Session(*key)
                self._sessions[key] = s
                if len(self._sessions) > 64:
                    for k in [k for k, v in self._sessions.items() if v.conn is None and v is not s][:1]:
                        del self._sessions[k]
            old = s.conn
            s.conn = conn
            self._current = s
            welcome = {"type": "welcome", "version": PROTOCOL_VERSION, "last_seq": s.last_seq,
                       "last_event": s.last_event, "session": s.id, "aac": self.name}
            self._reply(conn, welcome)
            last = msg.get("last_event")
            if _is_int(last):
                start = 0 if (msg.get("session") not in (None, s.id)) else last
                if start > 0:
                    s.outbox = [(n, l) for (n, l) in s.outbox if n > start]
                for n, line in s.outbox:
                    if n > start:
                        conn.send(line)
        if old is not None:
            self._error(old, "replaced", "another connection took over this session")
            old.close()
        self.log("%s: %s session %s (mission `%s`, run `%s`, last seq %d)"
                 % (conn.peer, "new" if created else "resumed", s.id, key[0], key[1], s.last_seq))
        return s

    def _action(self, conn, session, msg):
        seq = msg["seq"]
        with self._lock:
            duplicate = seq <= session.last_seq
        if duplicate:
            self.log("duplicate action seq %d (already executed): acknowledged, not executed" % seq)
            self._reply(conn, {"type": "ack", "seq": seq})
            return
        action = {k: msg[k] for k in ("seq", "action", "primitive", "command", "params", "task", "call_site")}
        try:
            if self.on_action is not None:
                self.on_action(self, action)
        except Exception:
            self.log("on_action failed for seq %d:\n%s" % (seq, traceback.format_exc()))
            self._error(conn, "unavailable", "the vehicle could not execute this action", seq)
            return
        with self._lock:
            session.last_seq = max(session.last_seq, seq)
        self.log("executed seq=%d %s (%s %s)" % (seq, msg["action"], msg["primitive"], msg["command"]))
        self._reply(conn, {"type": "ack", "seq": seq})


# ---------------------------------------------------------------------------
# Demo: a trivial vehicle
# ---------------------------------------------------------------------------

def default_event(primitive):
    """`XyzPrimitive` -> `eventXyzOk` (the naming of examples/vehicle.mcl)."""
    base = primitive[:-len("Primitive")] if primitive.endswith("Primitive") else primitive
    return "event%sOk" % base


class TrivialVehicle(object):
    """Every enable ends ok after `delay` seconds; a disable before then cancels it.

    Each answer names its activation (the seq of the enable), and a run that
    was disabled never answers, even if its timer was already firing.
    """

    def __init__(self, mapping, delay):
        self.mapping = mapping
        self.delay = delay
        self.timers = {}  # key -> (timer, activation seq)
        self.lock = threading.Lock()

    def __call__(self, server, action):
        key = action.get("task") or action["primitive"]
        with self.lock:
            old = self.timers.pop(key, None)
        if old is not None:
            old[0].cancel()
        if action["command"] != "enable":
            return
        event = self.mapping.get(action["primitive"], default_event(action["primitive"]))
        if not event:
            return  # mapped to nothing: this primitive never answers
        timer = threading.Timer(self.delay, self._fire, args=(server, key, event, action["seq"]))
        timer.daemon = True
        with self.lock:
            self.timers[key] = (timer, action["seq"])
        timer.start()

    def _fire(self, server, key, event, activation):
        with self.lock:
            current = self.timers.get(key)
            if current is None or current[1] != activation:
                return  # disabled (or restarted) since: say nothing
            del self.timers[key]
            # Sent under the lock: a disable handled after this point comes
            # after the event, as on the wire.
            server.send_event(event, activation=activation)


def _split_addr(addr):
    host, _, port = addr.rpartition(":")
    return host.strip("[]") or "127.0.0.1", int(port)


def main(argv=None):
    p = argparse.ArgumentParser(description="A trivial AAC speaking the MCL AAC protocol v1 (docs/aac-protocol.md).")
    p.add_argument("--listen", default=DEFAULT_ADDR, help="HOST:PORT to listen on (port 0: any free port)")
    p.add_argument("--token", help="shared secret the player must send")
    p.add_argument("--map", action="append", default=[], metavar="PRIMITIVE=EVENT",
                   help="event that ends an enable of PRIMITIVE (empty: never answers); repeatable")
    p.add_argument("--map-file", help="JSON object {primitive: event}")
    p.add_argument("--delay", type=float, default=0.1, help="seconds before an enable ends ok")
    p.add_argument("--timeout", type=float, default=DEFAULT_TIMEOUT, help="seconds of silence before a player is dropped")
    p.add_argument("-v", "--verbose", action="store_true", help="log every message")
    args = p.parse_args(argv)

    mapping = {}
    if args.map_file:
        with open(args.map_file) as f:
            mapping.update(json.load(f))
    for m in args.map:
        prim, sep, event = m.partition("=")
        if not sep:
            p.error("--map `%s`: expected PRIMITIVE=EVENT" % m)
        mapping[prim] = event
    host, port = _split_addr(args.listen)
    server = AacServer(host, port, token=args.token, on_action=TrivialVehicle(mapping, args.delay),
                       timeout=args.timeout, verbose=args.verbose)
    # The first line of standard output is for scripts that listen on port 0.
    print("listening on %s:%d" % server.address)
    sys.stdout.flush()
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        server.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())

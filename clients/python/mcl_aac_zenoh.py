#!/usr/bin/env python3
"""Reference AAC (vehicle side) of the MCL AAC protocol over Zenoh.

Needs the Zenoh Python binding (``pip install eclipse-zenoh``) and
``mcl_aac.py`` beside this file (message checks, the trivial vehicle).
The messages are those of docs/aac-protocol.md, the same JSON objects; the
keys and the rules that replace the TCP connection are in docs/zenoh.md:

* the player publishes on ``mcl/<vehicle>/aac/player/<type>`` (``hello``,
  ``action``, ``ping``), each message with the field ``run``;
* this AAC publishes on ``mcl/<vehicle>/aac/vehicle/<type>`` (``welcome``,
  ``ack``, ``event``, ``perception``, ``pong``, ``error``), each message
  with the ``run`` it answers and the ``session``;
* an action is executed only when its ``seq`` is the next one
  (``last_seq + 1``); one already executed is acknowledged again; one after
  a gap is dropped (the player publishes it again every second);
* events and perceptions are numbered ``n`` and kept until the player
  confirms them (``ping.last_event``); every ping re-sends those published
  more than a second ago and not yet confirmed.

Use it as a library, like ``mcl_aac.AacServer``::

    from mcl_aac_zenoh import ZenohAac

    aac = ZenohAac("auv", connect=["tcp/127.0.0.1:7447"], on_action=on_action)
    aac.start()

``on_action(aac, action)`` is called once per action, in ``seq`` order;
``aac.send_event(name, activation=seq)`` and ``aac.send_perception(name,
value)`` may be called from any thread.

Run as a program, it is the trivial vehicle of ``mcl_aac.py`` over Zenoh
(see ``--help``); its first line on standard output is ``listening on
...`` once it subscribes.
"""

import argparse
import json
import os
import sys
import threading
import time
import traceback

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import mcl_aac  # noqa: E402  (beside this file)
import zenoh  # noqa: E402

RESEND_AFTER = 1.0  # seconds before an unconfirmed event is published again


def config(connect=(), listen=(), config_file=None, mode="peer"):
    """A Zenoh configuration: the file's (or Zenoh's defaults), with the endpoints given.

    With endpoints and no file, multicast scouting is off (as in `mcl run`).
    """
    conf = zenoh.Config.from_file(config_file) if config_file else zenoh.Config()
    if not config_file or mode != "peer":
        conf.insert_json5("mode", json.dumps(mode))
    if connect:
        conf.insert_json5("connect/endpoints", json.dumps(list(connect)))
    if listen:
        conf.insert_json5("listen/endpoints", json.dumps(list(listen)))
    if not config_file and (connect or listen):
        conf.insert_json5("scouting/multicast/enabled", "false")
    return conf


class _Session(object):
    """One run of one mission."""

    def __init__(self, mission, run):
        self.mission = mission
        self.run = run
        self.id = "%x-%x-%s" % (int(time.time() * 1e6), os.getpid(), os.urandom(3).hex())
        self.last_seq = 0
        self.last_event = 0
        # [n, message dict, last published (monotonic seconds)] not yet confirmed.
        self.outbox = []


class ZenohAac(object):
    """An AAC over Zenoh for vehicle `vehicle`: see the module documentation."""

    def __init__(self, vehicle, connect=(), listen=(), config_file=None, token=None, on_action=None,
                 log=mcl_aac._log_stderr, verbose=False, name="mcl_aac_zenoh.py/1", mode="peer",
                 max_outbox=mcl_aac.MAX_OUTBOX):
        if not vehicle or any(c in vehicle for c in "/*$?#") or vehicle.startswith("@"):
            raise ValueError("vehicle `%s` cannot be a chunk of a Zenoh key" % vehicle)
        self.vehicle = vehicle
        self.conf = config(connect, listen, config_file, mode)
        self.token = token
        self.on_action = on_action
        self.log = log or (lambda msg: None)
        self.verbose = verbose
        self.name = name
        self.max_outbox = max_outbox
        self._lock = threading.RLock()  # the sessions' state
        self._handling = threading.Lock()  # one player message at a time
        self._sessions = {}  # (mission, run) -> _Session
        self._current = None
        self._zenoh = None
        self._sub = None

    # -- the vehicle side's API -------------------------------------------

    def send_event(self, name, session=None, activation=None):
        """Sends event `name` (numbered, kept until confirmed) to the player of the latest session."""
        msg = {"type": "event", "event": name}
        if activation is not None:
            msg["activation"] = activation
        self._push(session, msg)

    def send_perception(self, name, value, session=None):
        """Sends perception `name` with a JSON value."""
        self._push(session, {"type": "perception", "name": name, "value": value})

    def start(self):
        """Opens the Zenoh session and subscribes to the player's messages."""
        self._zenoh = zenoh.open(self.conf)
        self._sub = self._zenoh.declare_subscriber("mcl/%s/aac/player/*" % self.vehicle, self._on_sample)
        return self

    def close(self):
        if self._zenoh is not None:
            self._zenoh.close()
            self._zenoh = None

    # -- internals ----------------------------------------------------------

    def _publish(self, msg):
        data = json.dumps(msg, separators=(",", ":"), ensure_ascii=False)
        if self.verbose:
            self.log("-> %s" % data)
        z = self._zenoh
        if z is not None:
            try:
                z.put("mcl/%s/aac/vehicle/%s" % (self.vehicle, msg["type"]), data)
            except Exception as e:  # a closed session: the player's re-sends recover
                self.log("cannot publish: %s" % e)

    def _reply(self, session, msg, run=None):
        if session is not None:
            msg["run"] = session.run
            msg["session"] = session.id
        elif run is not None:
            msg["run"] = run
        self._publish(msg)

    def _error(self, code, message, seq=None, run=None):
        self.log("%s: %s" % (code, message))
        msg = {"type": "error", "code": code, "message": message}
        if seq is not None:
            msg["seq"] = seq
        self._reply(None, msg, run)

    def _push(self, session, msg):
        with self._lock:
            s = session or self._current
            if s is None:
                self.log("no session yet: dropped %s" % json.dumps(msg))
                return
            s.last_event += 1
            msg["n"] = s.last_event
            msg["run"] = s.run
            msg["session"] = s.id
            s.outbox.append([s.last_event, msg, time.monotonic()])
            if len(s.outbox) > self.max_outbox:
                del s.outbox[:len(s.outbox) - self.max_outbox]
        self._publish(msg)

    def _by_run(self, run):
        with self._lock:
            for s in self._sessions.values():
                if s.run == run:
                    return s
        return None

    def _on_sample(self, sample):
        data = sample.payload.to_bytes()
        with self._handling:
            try:
                self._handle(data)
            except Exception:
                self.log("failed on a player message:\n%s" % traceback.format_exc())

    def _handle(self, data):
        if self.verbose:
            self.log("<- %s" % data.decode("utf-8", "replace"))
        try:
            msg = mcl_aac.parse_line(data)
        except mcl_aac.ProtocolError as e:
            self._error(e.code, e.message, e.seq)
            return
        run = msg.get("run") if isinstance(msg.get("run"), str) else None
        ty = msg["type"]
        if ty == "hello":
            self._hello(msg)
        elif ty in ("action", "ping"):
            s = self._by_run(run) if run is not None else None
            if s is None:
                # A run this AAC does not know (it restarted): the player says hello again.
                self._error("unexpected", "no session for run `%s`: say hello" % (run or ""), msg.get("seq"), run)
            elif ty == "action":
                self._action(s, msg)
            else:
                self._ping(s, msg)
        # welcome, ack, event, perception, pong, error from a player: ignored.

    def _hello(self, msg):
        run = msg.get("run")
        if msg["version"] != mcl_aac.PROTOCOL_VERSION:
            self._error("version", "this AAC speaks protocol version %d, not %s"
                        % (mcl_aac.PROTOCOL_VERSION, msg["version"]), run=run)
            return
        if self.token is not None and msg.get("token") != self.token:
            self._error("unauthorized", "wrong token" if "token" in msg else "this AAC requires a token", run=run)
            return
        key = (str(msg.get("mission") or ""), str(run or ""))
        with self._lock:
            s = self._sessions.get(key)
            created = s is None
            if created:
                s = _Session(*key)
                self._sessions[key] = s
            self._current = s
            welcome = {"type": "welcome", "version": mcl_aac.PROTOCOL_VERSION, "last_seq": s.last_seq,
                       "last_event": s.last_event, "session": s.id, "aac": self.name}
            self._reply(s, welcome)
            last = msg.get("last_event")
            if mcl_aac._is_int(last):
                start = 0 if msg.get("session") not in (None, s.id) else last
                if start > 0:
                    s.outbox = [e for e in s.outbox if e[0] > start]
                now = time.monotonic()
                for e in s.outbox:
                    if e[0] > start:
                        e[2] = now
                        self._publish(e[1])
        if created:
            self.log("new session %s (mission `%s`, run `%s`)" % (s.id, key[0], key[1]))

    def _action(self, s, msg):
        seq = msg["seq"]
        with self._lock:
            last = s.last_seq
        if seq <= last:
            self.log("duplicate action seq %d (already executed): acknowledged, not executed" % seq)
            self._reply(s, {"type": "ack", "seq": seq})
            return
        if seq != last + 1:
            if self.verbose:
                self.log("action seq %d after a gap (last executed %d): waits for its re-send" % (seq, last))
            return
        action = {k: msg[k] for k in ("seq", "action", "primitive", "command", "params", "task", "call_site")}
        try:
            if self.on_action is not None:
                self.on_action(self, action)
        except Exception:
            self.log("on_action failed for seq %d:\n%s" % (seq, traceback.format_exc()))
            self._error("unavailable", "the vehicle could not execute this action", seq, s.run)
            return
        with self._lock:
            s.last_seq = seq
        self.log("executed seq=%d %s (%s %s)" % (seq, msg["action"], msg["primitive"], msg["command"]))
        self._reply(s, {"type": "ack", "seq": seq})

    def _ping(self, s, msg):
        last = msg.get("last_event")
        again = []
        with self._lock:
            if mcl_aac._is_int(last):
                s.outbox = [e for e in s.outbox if e[0] > last]
            now = time.monotonic()
            for e in s.outbox:
                if now - e[2] >= RESEND_AFTER:
                    e[2] = now
                    again.append(e[1])
        self._reply(s, {"type": "pong"})
        for m in again:
            self._publish(m)


def main(argv=None):
    p = argparse.ArgumentParser(description="A trivial AAC speaking the MCL AAC protocol over Zenoh (docs/zenoh.md).")
    p.add_argument("--vehicle", required=True, help="the vehicle's name in the keys mcl/<vehicle>/aac/...")
    p.add_argument("--connect", action="append", default=[], metavar="ENDPOINT",
                   help="Zenoh endpoint to connect to, e.g. tcp/127.0.0.1:7447 (repeatable)")
    p.add_argument("--listen", action="append", default=[], metavar="ENDPOINT",
                   help="Zenoh endpoint to listen on (repeatable)")
    p.add_argument("--config", help="a Zenoh configuration file (JSON5)")
    p.add_argument("--mode", default="peer", choices=["peer", "client"], help="Zenoh mode")
    p.add_argument("--token", help="shared secret the player must send")
    p.add_argument("--map", action="append", default=[], metavar="PRIMITIVE=EVENT",
                   help="event that ends an enable of PRIMITIVE (empty: never answers); repeatable")
    p.add_argument("--map-file", help="JSON object {primitive: event}")
    p.add_argument("--delay", type=float, default=0.1, help="seconds before an enable ends ok")
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
    aac = ZenohAac(args.vehicle, connect=args.connect, listen=args.listen, config_file=args.config,
                   token=args.token, on_action=mcl_aac.TrivialVehicle(mapping, args.delay),
                   verbose=args.verbose, mode=args.mode)
    aac.start()
    where = ", ".join(args.listen + args.connect) or "zenoh"
    print("listening on %s" % where)
    sys.stdout.flush()
    try:
        while True:
            time.sleep(3600)
    except KeyboardInterrupt:
        aac.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())

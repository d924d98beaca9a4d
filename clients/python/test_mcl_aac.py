"""Unit tests of the reference AAC (standard library only).

    python3 -m unittest discover -s clients/python -p 'test_*.py'

Run by `cargo test --test aac_python` too; the wire-level conformance suite
is in tests/aac_common/mod.rs.
"""

import threading
import time
import unittest

import mcl_aac
from mcl_aac import ProtocolError, TrivialVehicle, parse_line


def code_of(line):
    try:
        parse_line(line)
    except ProtocolError as e:
        return e.code
    return None


class ParseLine(unittest.TestCase):
    def test_hello_version_must_be_an_integer(self):
        self.assertEqual(parse_line(b'{"type":"hello","version":1}')["version"], 1)
        # JSON true is a bool, and bool is an int subclass in Python: refused.
        for v in (b"true", b"false", b'"1"', b"1.0", b"null", b"-1", b"[1]"):
            self.assertEqual(code_of(b'{"type":"hello","version":' + v + b"}"), "malformed", v)
        self.assertEqual(code_of(b'{"type":"hello"}'), "malformed")

    def test_other_integers_refuse_bools(self):
        self.assertEqual(code_of(b'{"type":"hello","version":1,"last_event":true}'), "malformed")
        self.assertEqual(code_of(b'{"type":"ping","last_event":false}'), "malformed")
        self.assertEqual(parse_line(b'{"type":"ping","last_event":3}')["last_event"], 3)
        e = None
        try:
            parse_line(b'{"type":"action","seq":true,"action":"a","primitive":"P","command":"enable"}')
        except ProtocolError as err:
            e = err
        self.assertIsNotNone(e)
        self.assertEqual((e.code, e.seq), ("malformed", None))

    def test_unknown_and_malformed(self):
        self.assertEqual(code_of(b"{oops"), "malformed")
        self.assertEqual(code_of(b'{"type":"teleport"}'), "unknown_type")
        self.assertEqual(code_of(b'{"type":"hello","version":1,"token":5}'), "malformed")


class FakeServer(object):
    """Records what a vehicle sends."""

    def __init__(self):
        self.events = []
        self.lock = threading.Lock()

    def send_event(self, name, session=None, activation=None):
        with self.lock:
            self.events.append((name, activation))


def action(seq, command, primitive="GotoPrimitive", task="Goto"):
    return {"seq": seq, "action": command + task, "primitive": primitive, "command": command,
            "params": {}, "task": task, "call_site": 1}


def wait_for(pred, limit=5.0):
    deadline = time.time() + limit
    while time.time() < deadline:
        if pred():
            return True
        time.sleep(0.01)
    return pred()


class Vehicle(unittest.TestCase):
    def test_answers_name_their_activation(self):
        server = FakeServer()
        v = TrivialVehicle({}, 0.01)
        v(server, action(1, "enable"))
        self.assertTrue(wait_for(lambda: server.events))
        self.assertEqual(server.events, [("eventGotoOk", 1)])

    def test_a_disabled_run_never_answers(self):
        server = FakeServer()
        v = TrivialVehicle({}, 0.2)
        v(server, action(1, "enable"))
        v(server, action(2, "disable"))
        v(server, action(3, "enable", "DepthPrimitive", "Depth"))
        self.assertTrue(wait_for(lambda: server.events))
        time.sleep(0.3)
        self.assertEqual(server.events, [("eventDepthOk", 3)])

    def test_a_stale_timer_says_nothing(self):
        # The timer of run 1 fires after run 1 was disabled and run 4 started
        # (cancel() cannot stop a timer already running): it stays silent.
        server = FakeServer()
        v = TrivialVehicle({}, 10.0)
        v(server, action(1, "enable"))
        v(server, action(2, "disable"))
        v(server, action(4, "enable"))
        v._fire(server, "Goto", "eventGotoOk", 1)
        self.assertEqual(server.events, [])
        v._fire(server, "Goto", "eventGotoOk", 4)
        self.assertEqual(server.events, [("eventGotoOk", 4)])
        v(server, action(5, "disable"))


class Server(unittest.TestCase):
    def test_events_carry_their_activation_on_the_wire(self):
        import json
        import socket
        server = mcl_aac.AacServer("127.0.0.1", 0, log=None)
        server.start()
        try:
            sock = socket.create_connection(server.address, timeout=5)
            f = sock.makefile("rb")
            sock.sendall(b'{"type":"hello","version":1,"mission":"m","run":"r"}\n')
            self.assertEqual(json.loads(f.readline())["type"], "welcome")
            server.send_event("eventGotoOk", activation=7)
            server.send_event("alarm")
            self.assertEqual(json.loads(f.readline()), {"type": "event", "event": "eventGotoOk", "activation": 7, "n": 1})
            self.assertEqual(json.loads(f.readline()), {"type": "event", "event": "alarm", "n": 2})
            # A hello-like line with a bool version, in a session: still an error, never a crash.
            sock.sendall(b'{"type":"hello","version":true}\n')
            reply = json.loads(f.readline())
            self.assertEqual((reply["type"], reply["code"]), ("error", "malformed"))
            sock.close()
        finally:
            server.close()

    def test_a_resumed_player_gets_what_followed_its_last_event(self):
        # Events sent while no player is connected are kept (at most
        # max_outbox), and a hello naming the session and its last event
        # gets those after it again; another session's name gets them all.
        import json
        import socket
        server = mcl_aac.AacServer("127.0.0.1", 0, log=None, max_outbox=3)
        server.start()
        try:
            def hello(extra):
                sock = socket.create_connection(server.address, timeout=5)
                f = sock.makefile("rb")
                h = {"type": "hello", "version": 1, "mission": "m", "run": "r"}
                h.update(extra)
                sock.sendall((json.dumps(h) + "\n").encode())
                return sock, f, json.loads(f.readline())

            sock, f, w = hello({})
            f.close()
            sock.close()
            self.assertTrue(wait_for(lambda: server._current is not None and server._current.conn is None))
            for i in range(5):
                server.send_event("e%d" % (i + 1))
            sock, f, w = hello({"session": w["session"], "last_event": 3})
            self.assertEqual((w["type"], w["last_event"]), ("welcome", 5))
            self.assertEqual([json.loads(f.readline())["n"] for _ in range(2)], [4, 5])
            f.close()
            sock.close()
            self.assertTrue(wait_for(lambda: server._current.conn is None))
            sock, f, w = hello({"session": "an older one", "last_event": 4})
            self.assertEqual([json.loads(f.readline())["event"] for _ in range(2)], ["e4", "e5"])
            f.close()
            sock.close()
        finally:
            server.close()


if __name__ == "__main__":
    unittest.main()

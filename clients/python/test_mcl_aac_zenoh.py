"""Tests of the reference AAC over Zenoh (mcl_aac_zenoh.py), with a player
written here from docs/zenoh.md, over a loopback endpoint (no scouting).

Skipped without the Zenoh binding (`pip install eclipse-zenoh`), unless
MCL_REQUIRE_ZENOH_PY=1 (CI), which makes its absence a failure.
"""

import json
import os
import queue
import socket
import sys
import time
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

try:
    import zenoh  # noqa: F401
    HAVE_ZENOH = True
except ImportError:
    HAVE_ZENOH = False
    if os.environ.get("MCL_REQUIRE_ZENOH_PY") == "1":
        raise

WAIT = 10.0


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


@unittest.skipUnless(HAVE_ZENOH, "the Zenoh binding is not installed (pip install eclipse-zenoh)")
class ZenohAacTest(unittest.TestCase):
    def setUp(self):
        import mcl_aac
        import mcl_aac_zenoh
        endpoint = "tcp/127.0.0.1:%d" % free_port()
        self.logs = []
        self.aac = mcl_aac_zenoh.ZenohAac("v1", listen=[endpoint], log=self.logs.append,
                                          on_action=mcl_aac.TrivialVehicle({}, 0.05)).start()
        self.player = zenoh.open(mcl_aac_zenoh.config(connect=[endpoint], listen=["tcp/127.0.0.1:0"]))
        self.inbox = queue.Queue()
        self.player.declare_subscriber(
            "mcl/v1/aac/vehicle/*", lambda s: self.inbox.put(json.loads(s.payload.to_bytes())))
        self.run_id = "r1"

    def tearDown(self):
        self.player.close()
        self.aac.close()

    def send(self, msg):
        msg = dict(msg, run=self.run_id)
        self.player.put("mcl/v1/aac/player/%s" % msg["type"], json.dumps(msg))

    def expect(self, ty, resend=None):
        """The next message of type `ty` (others skipped), publishing `resend` every 0.5 s meanwhile."""
        deadline = time.monotonic() + WAIT
        last = 0.0
        while time.monotonic() < deadline:
            if resend is not None and time.monotonic() - last > 0.5:
                self.send(resend)
                last = time.monotonic()
            try:
                m = self.inbox.get(timeout=0.1)
            except queue.Empty:
                continue
            if m["type"] == ty:
                return m
        self.fail("no `%s` within %.0f s; log: %s" % (ty, WAIT, self.logs))

    def test_a_session_executes_in_order_once_and_numbers_its_events(self):
        hello = {"type": "hello", "version": 1, "mission": "m", "last_event": 0}
        w = self.expect("welcome", resend=hello)
        self.assertEqual((w["last_seq"], w["run"]), (0, "r1"))
        act = {"type": "action", "action": "enableGoto", "primitive": "GotoPrimitive", "command": "enable",
               "params": {}}
        # After a gap: not executed, not acknowledged.
        self.send(dict(act, seq=2))
        self.send(dict(act, seq=1))
        self.assertEqual(self.expect("ack")["seq"], 1)
        ev = self.expect("event")
        self.assertEqual((ev["event"], ev["n"], ev["activation"], ev["session"]),
                         ("eventGotoOk", 1, 1, w["session"]))
        self.send(dict(act, seq=2))
        self.assertEqual(self.expect("ack")["seq"], 2)
        # A re-sent action is acknowledged again, not executed again.
        self.send(dict(act, seq=1))
        self.assertEqual(self.expect("ack")["seq"], 1)
        executed = [l for l in self.logs if l.startswith("executed seq=")]
        self.assertEqual(len(executed), 2, self.logs)
        # An unconfirmed event comes again with a ping; a confirmed one does not.
        time.sleep(1.1)
        while not self.inbox.empty():
            self.inbox.get()
        self.send({"type": "ping", "last_event": 1})
        self.assertEqual(self.expect("event")["n"], 2)
        self.send({"type": "ping", "last_event": 2})
        self.expect("pong")

    def test_an_unknown_run_is_told_to_say_hello(self):
        self.run_id = "unknown"
        e = self.expect("error", resend={"type": "ping", "last_event": 0})
        self.assertEqual((e["code"], e["run"]), ("unexpected", "unknown"))


if __name__ == "__main__":
    unittest.main()

#!/usr/bin/env python3
"""Event-to-action latency through the ROS 2 bridge on loopback, and through
the TCP AAC in the same run (BENCHMARKS.md, "mcl-ros2").

    python3 benches-scripts/ros2-latency.py MCL [ROUNDS]   (default 500)

MCL is the `mcl` binary to measure. Both runs play the same mission of
examples/vehicle.mcl with the same binary,

    mission { while ( Alarm() ) { Surface() } }

against a vehicle written in Python. Each round: the vehicle sees the Alarm
primitive enabled, takes t0 and raises the alarm event; the player ends
Alarm and enables Surface; the vehicle takes t1 when that action reaches it
(t1 - t0: event to action), then ends Surface ok and the loop starts again.
After the rounds it ends Alarm in fail, which ends the mission.

- ROS 2: `mcl run --ros2 BRIDGE.toml`; the vehicle is a Cyclone DDS
  participant (`pip install cyclonedds`, independent of MCL's RustDDS):
  the alarm is a `std_msgs/Bool` on /alarm, the action a `std_msgs/Bool`
  on /surface/cmd; the vehicle polls its readers without sleeping.
- TCP: `mcl run --aac`; the vehicle is the reference AAC
  (clients/python/mcl_aac.py): the event and the action are JSON lines.

Timestamps are Python's perf_counter on the vehicle's side; the first 20
rounds of each run are warm-up. Prints one Markdown row per transport (µs).
"""
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
WARMUP = 20

MISSION = 'import "%s";\n\nmission {\n    while ( Alarm() ) {\n        Surface()\n    }\n}\n'

BRIDGE = """node = "mcl_bench"
domain_id = %d

[primitives.AlarmPrimitive]
enable = { publish = "/alarm/watch", type = "std_msgs/msg/Bool", fields = { data = true } }
disable = { publish = "/alarm/watch", type = "std_msgs/msg/Bool", fields = { data = false } }
events = [
    { topic = "/alarm", type = "std_msgs/msg/Bool", when = "data == true", event = "eventAlarmOk" },
    { topic = "/alarm", type = "std_msgs/msg/Bool", when = "data == false", event = "eventAlarmFail" },
]

[primitives.SurfacePrimitive]
enable = { publish = "/surface/cmd", type = "std_msgs/msg/Bool", fields = { data = true } }
disable = { publish = "/surface/cmd", type = "std_msgs/msg/Bool", fields = { data = false } }
events = [{ topic = "/surface/done", type = "std_msgs/msg/Bool", when = "data == true", event = "eventSurfaceOk" }]
"""


def stats(name, lat):
    us = sorted(x * 1e6 for x in lat[WARMUP:])
    if not us:
        return "| %s | no samples |" % name
    q = lambda p: us[min(len(us) - 1, int(p * len(us)))]
    return "| %s | %d | %.0f | %.0f | %.0f | %.0f | %.0f |" % (
        name, len(us), q(0.5), q(0.9), q(0.99), statistics.mean(us), us[-1])


def run_ros2(mcl, mission, rounds, workdir):
    from dataclasses import dataclass
    from cyclonedds.core import Policy, Qos
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.idl import IdlStruct
    from cyclonedds.pub import DataWriter
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    @dataclass
    class Bool_(IdlStruct, typename="std_msgs::msg::dds_::Bool_"):
        data: bool

    domain = 1 + (os.getpid() + int(time.time())) % 200
    bridge = os.path.join(workdir, "BRIDGE.toml")
    with open(bridge, "w") as f:
        f.write(BRIDGE % domain)
    qos = Qos(Policy.Reliability.Reliable(1_000_000_000), Policy.Durability.TransientLocal, Policy.History.KeepLast(10))
    dp = DomainParticipant(domain)
    reader = lambda n: DataReader(dp, Topic(dp, n, Bool_, qos=qos), qos=qos)
    writer = lambda n: DataWriter(dp, Topic(dp, n, Bool_, qos=qos), qos=qos)
    watch, cmd = reader("rt/alarm/watch"), reader("rt/surface/cmd")
    alarm, done = writer("rt/alarm"), writer("rt/surface/done")
    p = subprocess.Popen([mcl, "run", "--ros2", bridge, mission, "--time-limit", "600", "-q"])
    lat, t0, n = [], None, 0
    while p.poll() is None:
        # An InvalidSample (no `data`) tells an instance's state change.
        for s in watch.take(10):
            if getattr(s, "data", False):
                if n < rounds + WARMUP:
                    t0 = time.perf_counter()
                    alarm.write(Bool_(data=True))
                else:
                    alarm.write(Bool_(data=False))
        for s in cmd.take(10):
            if getattr(s, "data", False) and t0 is not None:
                lat.append(time.perf_counter() - t0)
                t0 = None
                n += 1
                done.write(Bool_(data=True))
    if p.returncode != 0:
        sys.exit("mcl run --ros2 ended with status %d" % p.returncode)
    return lat


def run_tcp(mcl, mission, rounds):
    sys.path.insert(0, os.path.join(ROOT, "clients", "python"))
    from mcl_aac import AacServer

    lat, state = [], {"t0": None, "n": 0}

    def on_action(server, a):
        if a["command"] != "enable":
            return
        if a["primitive"] == "AlarmPrimitive":
            if state["n"] < rounds + WARMUP:
                state["t0"] = time.perf_counter()
                server.send_event("eventAlarmOk", activation=a["seq"])
            else:
                server.send_event("eventAlarmFail", activation=a["seq"])
        elif a["primitive"] == "SurfacePrimitive":
            lat.append(time.perf_counter() - state["t0"])
            state["n"] += 1
            server.send_event("eventSurfaceOk", activation=a["seq"])

    server = AacServer(port=0, on_action=on_action, log=None)
    server.start()
    host, port = server.address
    code = subprocess.call([mcl, "run", "--aac", "%s:%d" % (host, port), mission, "--time-limit", "600", "-q"])
    server.close()
    if code != 0:
        sys.exit("mcl run --aac ended with status %d" % code)
    return lat


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    mcl = os.path.abspath(sys.argv[1])
    rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 500
    with tempfile.TemporaryDirectory() as d:
        mission = os.path.join(d, "mission.mcl")
        with open(mission, "w") as f:
            f.write(MISSION % os.path.join(ROOT, "examples", "vehicle.mcl"))
        ros2 = run_ros2(mcl, mission, rounds, d)
        tcp = run_tcp(mcl, mission, rounds)
    print("| transport | rounds | p50 | p90 | p99 | mean | max |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    print(stats("ROS 2 bridge (RustDDS ↔ Cyclone DDS)", ros2))
    print(stats("TCP AAC (JSON lines)", tcp))


if __name__ == "__main__":
    main()

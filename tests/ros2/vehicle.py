"""A ROS 2 vehicle written with Eclipse Cyclone DDS (the `cyclonedds`
package from PyPI), independent of MCL's DDS stack: it publishes and
subscribes the ROS 2 topics `rt/...` with the ROS 2 type names.

    python3 vehicle.py DOMAIN SECONDS

Depth: a setpoint on /depth/setpoint (std_msgs/Float64) is answered on
/depth/reached with the same depth. Surface: `true` on /surface/cmd
(std_msgs/Bool) is answered "ok" on /surface/done (std_msgs/String).
Every message received is printed, one line each; `ready` once the
entities exist. The mission's state that the bridge publishes on
/mcl/status (std_msgs/String, JSON) is printed as `status JSON`.
"""
import sys
import time
from dataclasses import dataclass

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import float64, uint8
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic


@dataclass
class Bool_(IdlStruct, typename="std_msgs::msg::dds_::Bool_"):
    data: bool


@dataclass
class Float64_(IdlStruct, typename="std_msgs::msg::dds_::Float64_"):
    data: float64


@dataclass
class String_(IdlStruct, typename="std_msgs::msg::dds_::String_"):
    data: str


@dataclass
class Empty_(IdlStruct, typename="std_msgs::msg::dds_::Empty_"):
    structure_needs_at_least_one_member: uint8


QOS = Qos(Policy.Reliability.Reliable(1_000_000_000), Policy.Durability.TransientLocal, Policy.History.KeepLast(10))

dp = DomainParticipant(int(sys.argv[1]))
seconds = float(sys.argv[2])


def reader(name, ty):
    return DataReader(dp, Topic(dp, name, ty, qos=QOS), qos=QOS)


def writer(name, ty):
    return DataWriter(dp, Topic(dp, name, ty, qos=QOS), qos=QOS)


setpoint = reader("rt/depth/setpoint", Float64_)
stop = reader("rt/depth/stop", Empty_)
surface = reader("rt/surface/cmd", Bool_)
reached = writer("rt/depth/reached", Float64_)
done = writer("rt/surface/done", String_)
status = reader("rt/mcl/status", String_)
print("ready", flush=True)

end = time.time() + seconds
while time.time() < end:
    for s in setpoint.take(10):
        print(f"setpoint {s.data}", flush=True)
        reached.write(Float64_(data=s.data))
    for s in stop.take(10):
        print("stop", flush=True)
    for s in surface.take(10):
        print(f"surface {s.data}", flush=True)
        if s.data:
            done.write(String_(data="ok"))
    for s in status.take(10):
        print(f"status {s.data}", flush=True)
    time.sleep(0.01)

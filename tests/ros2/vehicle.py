"""A ROS 2 vehicle written with Eclipse Cyclone DDS (the `cyclonedds`
package from PyPI), independent of MCL's DDS stack: it publishes and
subscribes the ROS 2 topics `rt/...` with the ROS 2 type names.

    python3 vehicle.py DOMAIN SECONDS

Depth: a setpoint on /depth/setpoint (std_msgs/Float64) is answered on
/depth/reached with the same depth. Surface: `true` on /surface/cmd
(std_msgs/Bool) is answered "ok" on /surface/done (std_msgs/String).

Services (rmw_cyclonedds' mapping, `ros2dds.py`): /vehicle/initialize
(std_srvs/Trigger) answers success; /camera/enable (std_srvs/SetBool)
answers success; /camera/stuck (std_srvs/SetBool) never answers;
/vehicle/fix (std_srvs/Trigger) answers success.

`hostile` as a third argument: each depth setpoint is first answered, from
a second participant, by a `Float64` without its field and by a
`std_msgs/String` on /depth/reached, then (half a second later) rightly.

Every message and request received is printed, one line each; `ready`
once the entities exist.

The mission's state that the bridge publishes on /mcl/status
(std_msgs/String, JSON) is printed as `status JSON`.
"""
import sys
import time
from dataclasses import dataclass

from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import float64, int64, uint8, uint64

from ros2dds import ServiceServer, reader, writer


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


@dataclass
class Trigger_Request_(IdlStruct, typename="std_srvs::srv::dds_::Trigger_Request_"):
    guid: uint64
    seq: int64
    structure_needs_at_least_one_member: uint8


@dataclass
class Trigger_Response_(IdlStruct, typename="std_srvs::srv::dds_::Trigger_Response_"):
    guid: uint64
    seq: int64
    success: bool
    message: str


@dataclass
class SetBool_Request_(IdlStruct, typename="std_srvs::srv::dds_::SetBool_Request_"):
    guid: uint64
    seq: int64
    data: bool


@dataclass
class SetBool_Response_(IdlStruct, typename="std_srvs::srv::dds_::SetBool_Response_"):
    guid: uint64
    seq: int64
    success: bool
    message: str


@dataclass
class Float64WithoutData_(IdlStruct, typename="std_msgs::msg::dds_::Float64_"):
    flag: uint8


dp = DomainParticipant(int(sys.argv[1]))
seconds = float(sys.argv[2])
hostile = sys.argv[3:] == ["hostile"]
if hostile:
    dp2 = DomainParticipant(int(sys.argv[1]))
    short = writer(dp2, "rt/depth/reached", Float64WithoutData_)
    dp3 = DomainParticipant(int(sys.argv[1]))
    wrong = writer(dp3, "rt/depth/reached", String_)

setpoint = reader(dp, "rt/depth/setpoint", Float64_)
stop = reader(dp, "rt/depth/stop", Empty_)
surface = reader(dp, "rt/surface/cmd", Bool_)
reached = writer(dp, "rt/depth/reached", Float64_)
done = writer(dp, "rt/surface/done", String_)
initialize = ServiceServer(dp, "/vehicle/initialize", Trigger_Request_, Trigger_Response_)
camera = ServiceServer(dp, "/camera/enable", SetBool_Request_, SetBool_Response_)
stuck = ServiceServer(dp, "/camera/stuck", SetBool_Request_, SetBool_Response_)
fix = ServiceServer(dp, "/vehicle/fix", Trigger_Request_, Trigger_Response_)
status = reader(dp, "rt/mcl/status", String_)
print("ready", flush=True)

end = time.time() + seconds
while time.time() < end:
    # Samples without data (a writer that left) are skipped.
    for s in setpoint.take(10):
        if not hasattr(s, "data"):
            continue
        print(f"setpoint {s.data}", flush=True)
        if hostile:
            short.write(Float64WithoutData_(flag=1))
            wrong.write(String_(data="x"))
            time.sleep(0.5)
        reached.write(Float64_(data=s.data))
    for s in stop.take(10):
        if not hasattr(s, "structure_needs_at_least_one_member"):
            continue
        print("stop", flush=True)
    for s in surface.take(10):
        if not hasattr(s, "data"):
            continue
        print(f"surface {s.data}", flush=True)
        if s.data:
            done.write(String_(data="ok"))
    for r in initialize.take():
        print("initialize", flush=True)
        initialize.reply(r, success=True, message="initialized")
    for r in camera.take():
        print(f"camera {r.data}", flush=True)
        camera.reply(r, success=True, message="")
    for r in stuck.take():
        print("stuck", flush=True)
    for r in fix.take():
        print("fix", flush=True)
        fix.reply(r, success=True, message="")
    for s in status.take(10):
        print(f"status {s.data}", flush=True)
    time.sleep(0.01)

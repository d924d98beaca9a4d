"""A ROS 2 action server `/goto` of type auv_msgs/action/GoTo
(examples/ros2/interfaces), written on plain Eclipse Cyclone DDS (the
`cyclonedds` package from PyPI) as rmw_cyclonedds puts an action on DDS:
the services `/goto/_action/send_goal`, `get_result`, `cancel_goal` and the
topic `/goto/_action/feedback`.

    python3 goto_server.py DOMAIN SECONDS

What a goal does depends on its target's x:

- x < 0: rejected;
- x == 98: never answered (no acceptance, no rejection);
- x == 99: accepted, runs (with feedback) until cancelled;
- x == 97: accepted, one feedback, then the server's process ends at once
  (a crash: no goodbye on DDS; its lease runs out);
- x == 96: accepted, one feedback, then aborted;
- x == 94: accepted, one feedback, then cancelled by the server itself;
- x == 95: accepted, and `true` is published on /safety/alarm
  (std_msgs/Bool) after a moment; runs until cancelled;
- otherwise: accepted, three feedbacks (distance_to_target 3, 2, 1) a
  tenth of a second apart, then succeeded.

Each request and each end is printed, one line each, in the order the
server saw them (`goal X Y`, `cancel X`, `succeeded X`, ...); `ready` once
the entities exist.
"""
import os
import sys
import time
from dataclasses import dataclass

from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import array, float64, int8, int32, int64, sequence, uint8, uint32, uint64

from ros2dds import SERVICE_QOS, ServiceServer, writer


@dataclass
class Time_(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32
    nanosec: uint32


@dataclass
class Point_(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: float64
    y: float64
    z: float64


@dataclass
class UUID_(IdlStruct, typename="unique_identifier_msgs::msg::dds_::UUID_"):
    uuid: array[uint8, 16]


@dataclass
class GoalInfo_(IdlStruct, typename="action_msgs::msg::dds_::GoalInfo_"):
    goal_id: UUID_
    stamp: Time_


@dataclass
class GoTo_Goal_(IdlStruct, typename="auv_msgs::action::dds_::GoTo_Goal_"):
    target: Point_
    speed: float64


@dataclass
class GoTo_Result_(IdlStruct, typename="auv_msgs::action::dds_::GoTo_Result_"):
    reached: bool


@dataclass
class GoTo_Feedback_(IdlStruct, typename="auv_msgs::action::dds_::GoTo_Feedback_"):
    distance_to_target: float64


@dataclass
class SendGoal_Request_(IdlStruct, typename="auv_msgs::action::dds_::GoTo_SendGoal_Request_"):
    guid: uint64
    seq: int64
    goal_id: UUID_
    goal: GoTo_Goal_


@dataclass
class SendGoal_Response_(IdlStruct, typename="auv_msgs::action::dds_::GoTo_SendGoal_Response_"):
    guid: uint64
    seq: int64
    accepted: bool
    stamp: Time_


@dataclass
class GetResult_Request_(IdlStruct, typename="auv_msgs::action::dds_::GoTo_GetResult_Request_"):
    guid: uint64
    seq: int64
    goal_id: UUID_


@dataclass
class GetResult_Response_(IdlStruct, typename="auv_msgs::action::dds_::GoTo_GetResult_Response_"):
    guid: uint64
    seq: int64
    status: int8
    result: GoTo_Result_


@dataclass
class CancelGoal_Request_(IdlStruct, typename="action_msgs::srv::dds_::CancelGoal_Request_"):
    guid: uint64
    seq: int64
    goal_info: GoalInfo_


@dataclass
class CancelGoal_Response_(IdlStruct, typename="action_msgs::srv::dds_::CancelGoal_Response_"):
    guid: uint64
    seq: int64
    return_code: int8
    goals_canceling: sequence[GoalInfo_]


@dataclass
class FeedbackMessage_(IdlStruct, typename="auv_msgs::action::dds_::GoTo_FeedbackMessage_"):
    goal_id: UUID_
    feedback: GoTo_Feedback_


@dataclass
class Bool_(IdlStruct, typename="std_msgs::msg::dds_::Bool_"):
    data: bool


SUCCEEDED, CANCELED, ABORTED = 4, 5, 6

dp = DomainParticipant(int(sys.argv[1]))
seconds = float(sys.argv[2])
send_goal = ServiceServer(dp, "/goto/_action/send_goal", SendGoal_Request_, SendGoal_Response_)
get_result = ServiceServer(dp, "/goto/_action/get_result", GetResult_Request_, GetResult_Response_)
cancel_goal = ServiceServer(dp, "/goto/_action/cancel_goal", CancelGoal_Request_, CancelGoal_Response_)
feedback = writer(dp, "rt/goto/_action/feedback", FeedbackMessage_, SERVICE_QOS)
alarm = writer(dp, "rt/safety/alarm", Bool_)
print("ready", flush=True)


def say(line):
    print(line, flush=True)


class Goal:
    def __init__(self, gid, x):
        self.gid, self.x = gid, x
        self.steps = 0
        self.status = None  # the end, once there is one
        self.waiting = []  # get_result requests to answer at the end
        self.next = time.time() + 0.1


goals = {}  # goal id (bytes) -> Goal


def finish(g, status, word):
    g.status = status
    say(f"{word} {g.x:g}")
    for r in g.waiting:
        get_result.reply(r, status=status, result=GoTo_Result_(reached=status == SUCCEEDED))
    g.waiting = []


end = time.time() + seconds
while time.time() < end:
    for r in send_goal.take():
        x, y = r.goal.target.x, r.goal.target.y
        say(f"goal {x:g} {y:g}")
        gid = bytes(r.goal_id.uuid)
        if x == 98:
            continue
        accepted = x >= 0
        send_goal.reply(r, accepted=accepted, stamp=Time_(sec=0, nanosec=0))
        if accepted:
            goals[gid] = Goal(gid, x)
        else:
            say(f"rejected {x:g}")
    for r in get_result.take():
        g = goals.get(bytes(r.goal_id.uuid))
        if g is None:
            get_result.reply(r, status=0, result=GoTo_Result_(reached=False))
        elif g.status is not None:
            get_result.reply(r, status=g.status, result=GoTo_Result_(reached=g.status == SUCCEEDED))
        else:
            g.waiting.append(r)
    for r in cancel_goal.take():
        g = goals.get(bytes(r.goal_info.goal_id.uuid))
        if g is None or g.status is not None:
            say("cancel unknown")
            cancel_goal.reply(r, return_code=2, goals_canceling=[])
            continue
        say(f"cancel {g.x:g}")
        cancel_goal.reply(r, return_code=0, goals_canceling=[r.goal_info])
        finish(g, CANCELED, "canceled")
    now = time.time()
    for g in goals.values():
        if g.status is not None or now < g.next:
            continue
        g.next = now + 0.1
        g.steps += 1
        feedback.write(FeedbackMessage_(goal_id=UUID_(uuid=list(g.gid)), feedback=GoTo_Feedback_(distance_to_target=float(4 - g.steps))))
        if g.x == 97 and g.steps == 2:
            say("crash")
            os._exit(0)
        elif g.x == 96 and g.steps == 2:
            finish(g, ABORTED, "aborted")
        elif g.x == 94 and g.steps == 2:
            finish(g, CANCELED, "canceled")
        elif g.x == 95 and g.steps == 3:
            alarm.write(Bool_(data=True))
        elif g.x not in (94, 95, 96, 97, 99) and g.steps == 3:
            finish(g, SUCCEEDED, "succeeded")
    time.sleep(0.01)

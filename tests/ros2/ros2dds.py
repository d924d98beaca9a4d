"""ROS 2 on plain Eclipse Cyclone DDS (the `cyclonedds` package from PyPI),
shared by the test vehicles: QoS, and service servers as rmw_cyclonedds
puts them on DDS.

A service `/a/b` is the request topic `rq/a/bRequest` and the reply topic
`rr/a/bReply`, of types `pkg::srv::dds_::Name_Request_` and
`_Response_`. rmw_cyclonedds puts a 16-octet header before the request
(the client's GUID half and the request's sequence number, `guid` and `seq`
here); the server copies it into the reply, which is how the client finds
the request a reply answers.
"""
from cyclonedds.core import Policy, Qos
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic

# Topics: as the bridge's (reliable, transient-local, the last 10).
QOS = Qos(Policy.Reliability.Reliable(1_000_000_000), Policy.Durability.TransientLocal, Policy.History.KeepLast(10))
# Services and actions: as ROS 2's defaults (reliable, volatile).
SERVICE_QOS = Qos(Policy.Reliability.Reliable(1_000_000_000), Policy.Durability.Volatile, Policy.History.KeepLast(10))


def reader(dp, name, ty, qos=QOS):
    return DataReader(dp, Topic(dp, name, ty, qos=qos), qos=qos)


def writer(dp, name, ty, qos=QOS):
    return DataWriter(dp, Topic(dp, name, ty, qos=qos), qos=qos)


class ServiceServer:
    """The server end of service `name` (`/a/b`): `take()` the requests,
    `reply(request, **fields)` to one of them."""

    def __init__(self, dp, name, request_ty, response_ty):
        self.response_ty = response_ty
        self.requests = reader(dp, f"rq{name}Request", request_ty, SERVICE_QOS)
        self.replies = writer(dp, f"rr{name}Reply", response_ty, SERVICE_QOS)

    def take(self):
        # Samples without data (a client that left) are no requests.
        return [r for r in self.requests.take(10) if hasattr(r, "guid")]

    def reply(self, request, **fields):
        self.replies.write(self.response_ty(guid=request.guid, seq=request.seq, **fields))

//! Service calls of the bridge on the wire: one `ros2-client` client per
//! service, whose request and response bodies are the dynamic codec's
//! ([`RawCdr`], at offset 0: the mapping's header is written by a
//! serializer of its own).
//!
//! ROS 2 services are volatile: a request written before the server's
//! request reader is matched is lost. A call therefore waits until DDS
//! discovery has found the server's request reader and reply writer
//! ([`Discovered::ready`]), then for its response; both together take at most the
//! call's timeout, after which the call ends with an error that names what
//! was missing (no server, or no answer).

use super::discovery::{Discovered, Endpoints};
use super::{mapping, topic_name};
use crate::cdr;
use crate::idl::registry::dds_type_name;
use crate::idl::Registry;
use crate::raw::RawCdr;
use ros2_client::service::{Client, ServiceMapping};
use ros2_client::{Node, NodeName, ServiceTypeName};
use serde_json::Value;
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

/// The request and reply DDS topics of service `name` (`rq/...Request`,
/// `rr/...Reply`) as `ros2-client` names them for `node`, with the DDS type
/// names of `ty` (`pkg/srv/Name`, or an action's `pkg/action/Name_SendGoal`).
pub(super) fn endpoints(name: &ros2_client::Name, node: &NodeName, ty: &str) -> Endpoints {
    Endpoints {
        request: name.to_dds_name("rq", node, "Request"),
        request_type: dds_type_name(&format!("{ty}_Request")),
        reply: name.to_dds_name("rr", node, "Reply"),
        reply_type: dds_type_name(&format!("{ty}_Response")),
    }
}

/// `ServiceTypeName` of `pkg/srv/Name`.
fn service_type(full: &str) -> Result<ServiceTypeName, String> {
    match full.split('/').collect::<Vec<_>>().as_slice() {
        [pkg, "srv", name] => Ok(ServiceTypeName::new(pkg, name)),
        _ => Err(format!("`{full}` is not a service type `pkg/srv/Name`")),
    }
}

/// The QoS of service requests and replies (ROS 2's services default:
/// reliable, volatile, the last 10).
pub(super) fn service_qos() -> ros2_client::QosProfile {
    use ros2_client::qos::{Durability, History, WhenFull};
    ros2_client::QosProfile::publisher_default()
        .reliability_reliable(WhenFull::DEFAULT)
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 10 })
}

struct ServiceClient {
    ty: String,
    client: Client<RawCdr, RawCdr>,
    endpoints: Endpoints,
}

enum State {
    /// Waiting for the server to be discovered, with the encoded request.
    Unmatched(Vec<u8>),
    /// Sent; waiting for the response with this id.
    Sent(ros2_client::service::RmwRequestId),
}

struct Pending {
    call: u64,
    service: String,
    deadline: Instant,
    timeout: Duration,
    state: State,
}

/// The bridge's service clients and their calls under way.
pub(super) struct Services {
    mapping: ServiceMapping,
    clients: BTreeMap<String, ServiceClient>,
    pending: Vec<Pending>,
}

impl Services {
    pub(super) fn new(m: crate::bridge::config::Mapping) -> Services {
        Services { mapping: mapping(m), clients: BTreeMap::new(), pending: Vec::new() }
    }

    /// The client of `service` (type `ty`), created on first use: the node
    /// creates them all at its start, so that servers discover them early.
    pub(super) fn client(
        &mut self,
        node: &mut Node,
        node_name: &NodeName,
        service: &str,
        ty: &str,
    ) -> Result<(), String> {
        if !self.clients.contains_key(service) {
            let name = topic_name(service)?;
            let endpoints = endpoints(&name, node_name, ty);
            let client = node
                .create_client::<RawCdr, RawCdr>(self.mapping, &name, &service_type(ty)?, service_qos(), service_qos())
                .map_err(|e| format!("client of `{service}`: {e:?}"))?;
            self.clients.insert(service.to_string(), ServiceClient { ty: ty.to_string(), client, endpoints });
        }
        match self.clients.get(service) {
            Some(c) if c.ty != ty => Err(format!("service `{service}` is called as `{}`, not `{ty}`", c.ty)),
            _ => Ok(()),
        }
    }

    /// Starts call `call` of `service` (type `ty`) with `request`, sent at
    /// once if its server is matched; its answer comes from
    /// [`Services::poll`]. `Err`: the request cannot be encoded or the
    /// client cannot be created (the call is over).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn call(
        &mut self,
        node: &mut Node,
        node_name: &NodeName,
        reg: &Registry,
        discovered: &mut Discovered,
        call: u64,
        service: &str,
        ty: &str,
        request: &Value,
        timeout: Duration,
    ) -> Result<(), String> {
        let body = cdr::encode_body(reg, &format!("{ty}_Request"), request, 0).map_err(|e| e.to_string())?;
        self.client(node, node_name, service, ty)?;
        let now = Instant::now();
        self.pending.push(Pending {
            call,
            service: service.to_string(),
            deadline: now + timeout,
            timeout,
            state: State::Unmatched(body),
        });
        self.send_ready(discovered, now);
        Ok(())
    }

    /// Sends the calls whose server is matched; gives the calls that could
    /// not be sent, with why.
    fn send_ready(&mut self, discovered: &mut Discovered, now: Instant) -> Vec<(u64, Result<Value, String>)> {
        let mut failed = Vec::new();
        for p in &mut self.pending {
            let State::Unmatched(body) = &p.state else { continue };
            let Some(c) = self.clients.get(&p.service) else { continue };
            if !discovered.ready(&c.endpoints, now) {
                continue;
            }
            match c.client.send_request(RawCdr(body.clone())) {
                Ok(id) => p.state = State::Sent(id),
                Err(e) => failed.push((p.call, Err(format!("cannot send the request to `{}`: {e:?}", p.service)))),
            }
        }
        self.pending.retain(|p| !failed.iter().any(|(c, _)| *c == p.call));
        failed
    }

    /// Sends the calls whose server is now matched, and gives the calls
    /// that ended: a decoded response, or why there is none.
    pub(super) fn poll(
        &mut self,
        reg: &Registry,
        discovered: &mut Discovered,
        now: Instant,
    ) -> Vec<(u64, Result<Value, String>)> {
        let mut done = self.send_ready(discovered, now);
        // Responses, by the request they answer.
        let mut responses: BTreeMap<(String, ros2_client::service::RmwRequestId), Vec<u8>> = BTreeMap::new();
        for (name, c) in &self.clients {
            for _ in 0..256 {
                match c.client.receive_response() {
                    Ok(Some((id, RawCdr(body)))) => {
                        responses.insert((name.clone(), id), body);
                    }
                    Ok(None) => break,
                    // A reply without a readable request id answers no call we know.
                    Err(_) => continue,
                }
            }
        }
        let mut still = Vec::new();
        for p in std::mem::take(&mut self.pending) {
            let Some(c) = self.clients.get(&p.service) else { continue };
            if let State::Sent(id) = &p.state {
                if let Some(body) = responses.remove(&(p.service.clone(), *id)) {
                    let r = cdr::decode_body(reg, &format!("{}_Response", c.ty), &body, 0)
                        .map_err(|e| format!("the response of `{}` is not a `{}_Response`: {e}", p.service, c.ty));
                    done.push((p.call, r));
                    continue;
                }
            }
            if now >= p.deadline {
                let why = match p.state {
                    State::Unmatched(_) => discovered.why_not(&c.endpoints, p.timeout, now),
                    State::Sent(_) => format!("the server did not answer within {:.1} s", p.timeout.as_secs_f64()),
                };
                done.push((p.call, Err(format!("service `{}`: {why}", p.service))));
                continue;
            }
            still.push(p);
        }
        self.pending = still;
        done
    }

    /// Whether calls are under way.
    pub(super) fn busy(&self) -> bool {
        !self.pending.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The DDS names and types of a service and of an action's service,
    /// as rmw_cyclonedds and rmw_fastrtps name them.
    #[test]
    fn service_endpoints_follow_the_ros2_conventions() {
        let node = NodeName::new("/auv", "mcl").unwrap();
        let e = endpoints(&topic_name("/camera/enable").unwrap(), &node, "std_srvs/srv/SetBool");
        assert_eq!(
            e,
            Endpoints {
                request: "rq/camera/enableRequest".into(),
                request_type: "std_srvs::srv::dds_::SetBool_Request_".into(),
                reply: "rr/camera/enableReply".into(),
                reply_type: "std_srvs::srv::dds_::SetBool_Response_".into(),
            }
        );
        let e = endpoints(&topic_name("/goto/_action/send_goal").unwrap(), &node, "auv_msgs/action/GoTo_SendGoal");
        assert_eq!(
            (e.request.as_str(), e.reply_type.as_str()),
            ("rq/goto/_action/send_goalRequest", "auv_msgs::action::dds_::GoTo_SendGoal_Response_")
        );
        assert!(service_type("std_msgs/msg/Bool").is_err());
    }
}

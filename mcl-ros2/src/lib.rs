//! # mcl-ros2
//!
//! The ROS 2 side of MCL (issue 18), without a ROS installation:
//!
//! - [`idl`]: ROS 2 interface definitions (`.msg`, `.srv`, `.action` text),
//!   their parser, and a [`idl::Registry`] of resolved types with the
//!   bundled packages (`std_msgs`, `std_srvs`, `geometry_msgs`,
//!   `builtin_interfaces`, `action_msgs`, `unique_identifier_msgs`);
//! - [`cdr`]: dynamic CDR (XCDR1, little endian, with the 4-byte
//!   encapsulation header) of a JSON value against a registered type;
//! - [`bridge`]: the bridge file `BRIDGE.toml` that maps each primitive of a
//!   vehicle file to topics, services and actions, checked against the
//!   vehicle file and the message types with file and line, and the
//!   bridge as a sans-IO state machine;
//! - [`raw`]: an encoded body carried through a CDR serde serializer (the
//!   typed API of `ros2-client`/`rustdds`).
//!
//! - [`status`]: the mission's state on the status topic.
//!
//! All of it is sans-IO but `node`, the ROS 2 node of `mcl run --ros2`
//! (on `ros2-client`: topics, services, actions), and `raw`, which exist with the
//! feature `node` (on by default; the binary asks for it). Without it the
//! crate links no DDS: the language server checks bridge files with it.

pub mod bridge;
pub mod cdr;
pub mod idl;
#[cfg(feature = "node")]
pub mod node;
pub mod path;
#[cfg(feature = "node")]
pub mod raw;
pub mod status;

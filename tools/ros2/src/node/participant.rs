//! The DDS side: a participant on the settings' domain and interfaces, a
//! ROS 2 node in its namespace, and one publisher per topic with its QoS
//! ([`Outputs`]).

use std::net::{IpAddr, Ipv4Addr};
use std::time::Duration;

use ros2_client::dds::rustdds::DomainParticipantBuilder;
use ros2_client::dds::{Context, Node, Publisher};
use ros2_client::qos::{Durability, History, QosProfile, WhenFull};
use ros2_client::{MessageTypeName, Name, NodeName, NodeOptions};
use serde::Serialize;
use slope_tools::mount_transform::mount_to_transform;
use slope_tools::ros2_messages::{Header, SlopeEstimateMsg, TfMessage, Time, TransformStamped};

use super::settings::Settings;
use crate::diagnostics::DiagnosticArray;
use crate::discovery::DiscoveryRange;
use crate::markers::MarkerArray;
use crate::surfaces_msg::SurfacesMsg;
use crate::topics::{
    resolve, MessageType, DIAGNOSTICS_TOPIC, DIAGNOSTIC_ARRAY, ESTIMATE_TOPIC, MARKERS_TOPIC,
    MARKER_ARRAY, SLOPE_ESTIMATE, SURFACES, SURFACES_TOPIC, TF_MESSAGE, TF_STATIC_TOPIC,
};

/// How long a reliable publish may wait for room in the send window (a
/// reader that stopped acknowledging) before that message is dropped:
/// short, so that one stuck reader cannot hold up the others' topics.
const RELIABLE_WAIT: Duration = Duration::from_millis(50);

/// Messages a reliable topic keeps for readers that are behind or late.
const KEEP_LAST: usize = 10;

/// reliable, keep last 10, transient local: a late joiner (a planner
/// started after us, `ros2 topic echo`) gets the last 10 at once; volatile
/// readers match as well.
fn latched() -> QosProfile {
    QosProfile::publisher_default()
        .reliability_reliable(WhenFull::Wait(RELIABLE_WAIT))
        .durability(Durability::TransientLocal)
        .history(History::KeepLast { depth: KEEP_LAST })
}

/// reliable, keep last 10, volatile: what `diagnostic_updater` offers and
/// `diagnostic_aggregator` asks for.
fn reliable() -> QosProfile {
    QosProfile::publisher_default()
        .reliability_reliable(WhenFull::Wait(RELIABLE_WAIT))
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: KEEP_LAST })
}

/// best effort, keep last 1, volatile: pictures for rviz2, where a newer
/// frame makes an older one worthless.
fn best_effort() -> QosProfile {
    QosProfile::publisher_default()
        .reliability_best_effort()
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 1 })
}

/// reliable, keep last 1, transient local: what tf2's static broadcaster
/// offers and its listeners ask for.
fn tf_static() -> QosProfile {
    latched().history(History::KeepLast { depth: 1 })
}

/// The ROS 2 publishers of the node.
pub struct Outputs {
    pub estimate: Publisher<SlopeEstimateMsg>,
    pub surfaces: Publisher<SurfacesMsg>,
    pub diagnostics: Publisher<DiagnosticArray>,
    pub markers: Publisher<MarkerArray>,
    /// With `--base-frame`: the mount, published once (transient local:
    /// every late listener gets it).
    pub tf_static: Option<Publisher<TfMessage>>,
    /// Kept for the publishers' lifetime, dropped after them (fields drop
    /// in order): the node's participant ends with it.
    _node: Node,
}

impl Outputs {
    /// Joins the settings' DDS domain and creates the node and its
    /// publishers.
    pub fn create(settings: &Settings) -> anyhow::Result<Self> {
        let context = context(settings)?;
        let name = NodeName::new(&settings.namespace, &settings.node_name).map_err(|e| {
            anyhow::anyhow!(
                "cannot name the ROS 2 node {} in {}: {e:?}",
                settings.node_name,
                settings.namespace
            )
        })?;
        // No rosout (the log goes to stderr and the journal: one voice),
        // no parameter services (no spinner runs them; every setting is a
        // flag or a key of the config file).
        let options = NodeOptions::new()
            .enable_rosout(false)
            .start_parameter_services(false);
        let mut node = context
            .new_node(name, options)
            .map_err(|e| anyhow::anyhow!("cannot create the ROS 2 node: {e:?}"))?;
        let estimate = publisher(
            &mut node,
            &settings.namespace,
            ESTIMATE_TOPIC,
            SLOPE_ESTIMATE,
            latched(),
        )?;
        let surfaces = publisher(
            &mut node,
            &settings.namespace,
            SURFACES_TOPIC,
            SURFACES,
            latched(),
        )?;
        let diagnostics = publisher(
            &mut node,
            &settings.namespace,
            DIAGNOSTICS_TOPIC,
            DIAGNOSTIC_ARRAY,
            reliable(),
        )?;
        let markers = publisher(
            &mut node,
            &settings.namespace,
            MARKERS_TOPIC,
            MARKER_ARRAY,
            best_effort(),
        )?;
        let tf_static = match &settings.base_frame {
            Some(base) => {
                let publisher = publisher(
                    &mut node,
                    &settings.namespace,
                    TF_STATIC_TOPIC,
                    TF_MESSAGE,
                    tf_static(),
                )?;
                publisher
                    .publish(mount_message(settings, base)?)
                    .map_err(|e| anyhow::anyhow!("cannot publish the mount on /tf_static: {e}"))?;
                Some(publisher)
            }
            None => None,
        };
        Ok(Self {
            estimate,
            surfaces,
            diagnostics,
            markers,
            tf_static,
            _node: node,
        })
    }
}

/// `/tf_static`'s message: the camera's optical frame in `base`, from the
/// config file's `[mount]`, stamped now.
fn mount_message(settings: &Settings, base: &str) -> anyhow::Result<TfMessage> {
    let transform = mount_to_transform(&settings.mount).ok_or_else(|| {
        anyhow::anyhow!(
            "--base-frame {base} needs the camera's mount: height_m and pitch_deg (roll_deg \
             optional) in the config file's [mount]"
        )
    })?;
    let now_ns = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX));
    Ok(TfMessage {
        transforms: vec![TransformStamped {
            header: Header {
                stamp: Time::from_ns(now_ns),
                frame_id: base.to_string(),
            },
            child_frame_id: settings.frame_id.clone(),
            transform,
        }],
    })
}

/// The participant: the settings' domain; with a localhost range, the
/// loopback interface only (RustDDS then announces itself to this host's
/// well-known discovery ports, by unicast: the loopback has no multicast).
fn context(settings: &Settings) -> anyhow::Result<Context> {
    let discovery = &settings.discovery;
    let mut builder = DomainParticipantBuilder::new(discovery.domain_id);
    if discovery.range == DiscoveryRange::Localhost {
        builder = builder.with_only_networks([IpAddr::V4(Ipv4Addr::LOCALHOST)]);
    }
    let participant = builder.build().map_err(|e| {
        anyhow::anyhow!(
            "cannot join DDS domain {} ({} discovery): {e:?}",
            discovery.domain_id,
            discovery.range.name()
        )
    })?;
    Context::from_domain_participant(participant)
        .map_err(|e| anyhow::anyhow!("cannot start ROS 2 on the DDS participant: {e:?}"))
}

/// A publisher of `ty` on `topic` (resolved in `namespace`) with `qos`.
fn publisher<M: Serialize>(
    node: &mut Node,
    namespace: &str,
    topic: &str,
    ty: MessageType,
    qos: QosProfile,
) -> anyhow::Result<Publisher<M>> {
    let full = resolve(namespace, topic);
    let (parent, base) = full
        .rsplit_once('/')
        .ok_or_else(|| anyhow::anyhow!("topic {full} has no /"))?;
    let parent = if parent.is_empty() { "/" } else { parent };
    let name = Name::new(parent, base)
        .map_err(|e| anyhow::anyhow!("{full} is no ROS 2 topic name: {e:?}"))?;
    let topic = node
        .create_topic(&name, MessageTypeName::new(ty.package, ty.name), &qos)
        .map_err(|e| anyhow::anyhow!("cannot create the topic {full}: {e:?}"))?;
    node.create_publisher(&topic, Some(qos))
        .map_err(|e| anyhow::anyhow!("cannot publish on {full}: {e:?}"))
}

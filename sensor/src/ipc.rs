//! The iceoryx2 ports every slope process uses, configured in one place so
//! that whichever process comes first creates each service with the same
//! settings.
//!
//! Each topic is a publish-subscribe service plus an event service of the
//! same name; publishers notify after every send so subscribers can sleep in
//! a `WaitSet` instead of polling. Subscriber queues overflow safely (the
//! oldest sample is replaced): a slow subscriber never blocks a publisher.

use core::time::Duration;
use std::fmt::Debug;
use std::io::ErrorKind;

use iceoryx2::port::listener::{Listener, ListenerWaitError};
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::{Subscriber, SubscriberCreateError};
use iceoryx2::prelude::*;
use iceoryx2::sample::Sample;
use iceoryx2::service::port_factory::event::PortFactory as EventFactory;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory as PubSubFactory;
use slope_ipc_types::{
    now_ns, CloudHeader, CloudPoint, Health, ServiceNames, SlopeEstimate, Surfaces, SENSOR_NAME_LEN,
};

use crate::projection::Projector;
use crate::source::{SourceFrame, SourceInfo};

/// Most processes that may subscribe to clouds at once (estimator,
/// recorder, viewers).
pub const CLOUD_MAX_SUBSCRIBERS: usize = 6;
/// Clouds a subscriber may hold unread. Two: the one being processed may
/// be superseded by at most one newer one; older ones are stale anyway.
pub const CLOUD_SUBSCRIBER_BUFFER: usize = 2;
/// Clouds a recorder's subscriber may hold unread (the service's largest
/// subscriber buffer): 133 ms at 30 Hz, for a recorder that must lose none
/// while its receiving thread waits for a core. Each unit of it costs the
/// publisher [`CLOUD_MAX_SUBSCRIBERS`] more samples of shared memory.
pub const CLOUD_RECORDER_BUFFER: usize = 4;
/// Most processes that may subscribe to estimates at once.
pub const ESTIMATE_MAX_SUBSCRIBERS: usize = 16;
/// Estimates a subscriber may hold unread (about 2 s at 30 Hz).
pub const ESTIMATE_SUBSCRIBER_BUFFER: usize = 64;
/// Most processes that may subscribe to the surfaces at once.
pub const SURFACES_MAX_SUBSCRIBERS: usize = 16;
/// Surfaces messages a subscriber may hold unread: as many as estimates
/// (about 2 s at 30 Hz), so that a recorder that keeps every estimate
/// keeps their surfaces too (each is 3.2 kB: 3.3 MB of shared memory for
/// 16 subscribers).
pub const SURFACES_SUBSCRIBER_BUFFER: usize = ESTIMATE_SUBSCRIBER_BUFFER;
/// Daemons that may report on one health topic at once (estimator,
/// capture or replay, and a spare for a second recorder or a test).
pub const HEALTH_MAX_PUBLISHERS: usize = 4;
/// Most processes that may subscribe to health reports at once.
pub const HEALTH_MAX_SUBSCRIBERS: usize = 8;
/// Health reports a subscriber may hold unread (about 4 s of all daemons).
pub const HEALTH_SUBSCRIBER_BUFFER: usize = 16;

/// An iceoryx2 operation that failed, with the service (or node) it
/// concerned.
#[derive(Debug, thiserror::Error)]
#[error("failed to {action} on {kind} '{service}': {detail}")]
pub struct IpcError {
    pub action: &'static str,
    /// "service", or "node" for the process's own node.
    pub kind: &'static str,
    pub service: String,
    pub detail: String,
}

impl IpcError {
    fn new(action: &'static str, service: &str, detail: impl Debug) -> Self {
        Self {
            action,
            kind: "service",
            service: service.to_string(),
            detail: format!("{detail:?}"),
        }
    }
}

/// A cloud frame with more points than the configured maximum, or whose
/// size does not match the publisher's source.
#[derive(Debug, thiserror::Error)]
pub enum PublishFrameError {
    #[error(transparent)]
    Ipc(#[from] IpcError),
    #[error(
        "frame {index} is {width} x {height} but the source announced {expected_width} x {expected_height}"
    )]
    SizeMismatch {
        index: u64,
        width: u32,
        height: u32,
        expected_width: u32,
        expected_height: u32,
    },
}

/// Creates the process's iceoryx2 node. Signal handling is left to the
/// binaries (ctrlc), so iceoryx2 installs no handlers of its own.
pub fn create_node(name: &str) -> Result<Node<ipc::Service>, IpcError> {
    let node_error = |action, detail: String| IpcError {
        action,
        kind: "node",
        service: name.to_string(),
        detail,
    };
    let node_name = NodeName::new(name).map_err(|e| node_error("name", format!("{e:?}")))?;
    let node = NodeBuilder::new()
        .name(&node_name)
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<ipc::Service>()
        .map_err(|e| node_error("start iceoryx2", format!("{e:?}{}", root_path_hint())))?;
    // Resources of crashed processes would otherwise keep their ports
    // counted against the service limits.
    let cleanup = node.try_cleanup_dead_nodes();
    if cleanup.cleanups > 0 {
        tracing::info!(
            removed = cleanup.cleanups,
            "cleaned up resources of dead processes"
        );
    }
    Ok(node)
}

fn service_name(name: &str) -> Result<ServiceName, IpcError> {
    ServiceName::new(name).map_err(|e| IpcError::new("name the service", name, e))
}

type CloudService = PubSubFactory<ipc::Service, [CloudPoint], CloudHeader>;
type EstimateService = PubSubFactory<ipc::Service, SlopeEstimate, ()>;
type HealthService = PubSubFactory<ipc::Service, Health, ()>;
type SurfacesService = PubSubFactory<ipc::Service, Surfaces, ()>;

/// Why iceoryx2 may have failed to create a node, when it is the usual
/// reason: its root path (`/tmp/iceoryx2` by default) belongs to another
/// user, whose processes created it. Empty otherwise.
fn root_path_hint() -> String {
    use std::os::unix::fs::MetadataExt;
    let root = std::path::PathBuf::from(
        iceoryx2::config::Config::global_config()
            .global
            .root_path()
            .as_str(),
    );
    let denied = [root.clone(), root.join("nodes")]
        .iter()
        .any(|dir| std::fs::read_dir(dir).is_err_and(|e| e.kind() == ErrorKind::PermissionDenied));
    if !denied {
        return String::new();
    }
    let owner = std::fs::metadata(&root).map_or(String::from("another user"), |m| {
        format!("user id {}", m.uid())
    });
    format!(
        " ({} belongs to {owner}, whose slope processes created it: run every slope process and \
         every subscriber as that user, the systemd units' user; iceoryx2's files are their \
         owner's only)",
        root.display()
    )
}

fn cloud_service(node: &Node<ipc::Service>, name: &str) -> Result<CloudService, IpcError> {
    node.service_builder(&service_name(name)?)
        .publish_subscribe::<[CloudPoint]>()
        .user_header::<CloudHeader>()
        .max_publishers(1)
        .max_subscribers(CLOUD_MAX_SUBSCRIBERS)
        .subscriber_max_buffer_size(CLOUD_RECORDER_BUFFER)
        // The newest cloud so far plus the one just received.
        .subscriber_max_borrowed_samples(2)
        .history_size(0)
        .enable_safe_overflow(true)
        .open_or_create()
        .map_err(|e| IpcError::new("open or create the cloud service", name, e))
}

fn estimate_service(node: &Node<ipc::Service>, name: &str) -> Result<EstimateService, IpcError> {
    node.service_builder(&service_name(name)?)
        .publish_subscribe::<SlopeEstimate>()
        .max_publishers(1)
        .max_subscribers(ESTIMATE_MAX_SUBSCRIBERS)
        .subscriber_max_buffer_size(ESTIMATE_SUBSCRIBER_BUFFER)
        .subscriber_max_borrowed_samples(2)
        .history_size(0)
        .enable_safe_overflow(true)
        .open_or_create()
        .map_err(|e| IpcError::new("open or create the estimate service", name, e))
}

fn surfaces_service(node: &Node<ipc::Service>, name: &str) -> Result<SurfacesService, IpcError> {
    node.service_builder(&service_name(name)?)
        .publish_subscribe::<Surfaces>()
        .max_publishers(1)
        .max_subscribers(SURFACES_MAX_SUBSCRIBERS)
        .subscriber_max_buffer_size(SURFACES_SUBSCRIBER_BUFFER)
        .subscriber_max_borrowed_samples(2)
        .history_size(0)
        .enable_safe_overflow(true)
        .open_or_create()
        .map_err(|e| IpcError::new("open or create the surfaces service", name, e))
}

fn health_service(node: &Node<ipc::Service>, name: &str) -> Result<HealthService, IpcError> {
    node.service_builder(&service_name(name)?)
        .publish_subscribe::<Health>()
        .max_publishers(HEALTH_MAX_PUBLISHERS)
        .max_subscribers(HEALTH_MAX_SUBSCRIBERS)
        .subscriber_max_buffer_size(HEALTH_SUBSCRIBER_BUFFER)
        .subscriber_max_borrowed_samples(2)
        .history_size(0)
        .enable_safe_overflow(true)
        .open_or_create()
        .map_err(|e| IpcError::new("open or create the health service", name, e))
}

fn event_service(
    node: &Node<ipc::Service>,
    name: &str,
) -> Result<EventFactory<ipc::Service>, IpcError> {
    node.service_builder(&service_name(name)?)
        .event()
        .max_listeners(32)
        .max_notifiers(8)
        .open_or_create()
        .map_err(|e| IpcError::new("open or create the event service", name, e))
}

/// A listener on a topic's event service: what subscribers attach to a
/// `WaitSet` to wake on new data.
pub struct TopicListener {
    listener: Listener<ipc::Service>,
    service: String,
}

impl TopicListener {
    fn create(node: &Node<ipc::Service>, name: &str) -> Result<Self, IpcError> {
        let listener = event_service(node, name)?
            .listener_builder()
            .create()
            .map_err(|e| IpcError::new("create a listener", name, e))?;
        Ok(Self {
            listener,
            service: name.to_string(),
        })
    }

    /// The port to attach to a `WaitSet`.
    pub fn listener(&self) -> &Listener<ipc::Service> {
        &self.listener
    }

    /// Consumes pending notifications without blocking; returns how many.
    pub fn drain(&self) -> Result<u64, IpcError> {
        self.listener
            .try_wait(|_| {})
            .map_err(|e| IpcError::new("read notifications", &self.service, e))
    }

    /// Blocks until a notification arrives or `timeout` passes. A signal
    /// (SIGINT, SIGTERM) that interrupts the wait ends it early with no
    /// notification, not an error: the caller's stop flag decides what the
    /// signal means.
    pub fn wait(&self, timeout: Duration) -> Result<u64, IpcError> {
        match self.listener.timed_wait(|_| {}, timeout) {
            Err(ListenerWaitError::InterruptSignal) => Ok(0),
            result => result.map_err(|e| IpcError::new("wait for notifications", &self.service, e)),
        }
    }
}

fn create_notifier(
    node: &Node<ipc::Service>,
    name: &str,
) -> Result<Notifier<ipc::Service>, IpcError> {
    event_service(node, name)?
        .notifier_builder()
        .create()
        .map_err(|e| IpcError::new("create a notifier", name, e))
}

/// Publishes organised clouds, projecting depth straight into shared memory.
pub struct CloudPublisher {
    service: CloudService,
    publisher: Publisher<ipc::Service, [CloudPoint], CloudHeader>,
    notifier: Notifier<ipc::Service>,
    projector: Projector,
    info: SourceInfo,
    /// `info.sensor` as the header field, encoded once.
    sensor: [u8; SENSOR_NAME_LEN],
    name: String,
}

impl CloudPublisher {
    /// Creates the publisher for a source. Each sample holds exactly
    /// `width * height` points; sources larger than `max_points` are refused.
    pub fn create(
        node: &Node<ipc::Service>,
        names: &ServiceNames,
        info: &SourceInfo,
        max_points: usize,
    ) -> Result<Self, IpcError> {
        let name = names.cloud();
        let points = info.width as usize * info.height as usize;
        if points == 0 || points > max_points {
            return Err(IpcError::new(
                "create a publisher",
                &name,
                format!(
                    "a {} x {} frame has {points} points; the limit is {max_points} (--max-points)",
                    info.width, info.height
                ),
            ));
        }
        let service = cloud_service(node, &name)?;
        let publisher = service
            .publisher_builder()
            .initial_max_slice_len(points)
            .allocation_strategy(AllocationStrategy::Static)
            .max_loaned_samples(1)
            .create()
            .map_err(|e| {
                IpcError::new(
                    "create a publisher (is another source already publishing?)",
                    &name,
                    e,
                )
            })?;
        let notifier = create_notifier(node, &name)?;
        let projector = Projector::new(info.width, info.height, info.intrinsics, info.unit_m);
        Ok(Self {
            service,
            publisher,
            notifier,
            projector,
            sensor: CloudHeader::sensor_field(&info.sensor),
            info: info.clone(),
            name,
        })
    }

    /// Subscribers currently connected to the cloud service.
    pub fn subscriber_count(&self) -> usize {
        self.service.dynamic_config().number_of_subscribers()
    }

    pub fn service_name(&self) -> &str {
        &self.name
    }

    /// Projects `frame` into a loaned shared-memory sample and sends it.
    ///
    /// Zero-copy: every point is computed from the depth pixel and written
    /// once, in place, into the sample that subscribers will read; there is
    /// no intermediate cloud buffer.
    pub fn publish(&self, frame: &SourceFrame) -> Result<(), PublishFrameError> {
        let (width, height) = (self.info.width, self.info.height);
        let depth = &frame.depth;
        let points = self.projector.width() as usize * self.projector.height() as usize;
        if depth.width != width || depth.height != height || depth.data.len() != points {
            return Err(PublishFrameError::SizeMismatch {
                index: frame.index,
                width: depth.width,
                height: depth.height,
                expected_width: width,
                expected_height: height,
            });
        }
        let color = frame
            .color
            .as_ref()
            .filter(|c| c.width == width && c.height == height && c.data.len() == points);
        let mut sample = self
            .publisher
            .loan_slice_uninit(points)
            .map_err(|e| IpcError::new("loan a sample", &self.name, e))?;
        *sample.user_header_mut() = CloudHeader {
            frame_index: frame.index,
            capture_stamp_ns: frame.capture_stamp_ns,
            source_stamp_ns: frame.source_stamp_ns,
            width,
            height,
            intrinsics: self.info.intrinsics,
            mount: self.info.mount,
            source: self.info.source as u32,
            has_color: u32::from(color.is_some()),
            sensor: self.sensor,
        };
        // Row by row straight into the sample: a third of the time of a
        // per-pixel `write_from_fn` (which divides each index into a row and
        // a column), benches/projection.rs.
        let color = color.map(|c| c.data.as_slice());
        self.projector
            .project_into(&depth.data, color, sample.payload_mut());
        // SAFETY: `project_into` sets every element of the slice it is given,
        // whatever the lengths (its documented contract, tested in
        // projection.rs), so the whole payload is initialised.
        let sample = unsafe { sample.assume_init() };
        sample
            .send()
            .map_err(|e| IpcError::new("send a sample", &self.name, e))?;
        self.notifier
            .notify()
            .map_err(|e| IpcError::new("notify subscribers", &self.name, e))?;
        Ok(())
    }
}

/// A received cloud, read in place from shared memory.
pub struct CloudSample {
    sample: Sample<ipc::Service, [CloudPoint], CloudHeader>,
}

impl CloudSample {
    pub fn header(&self) -> &CloudHeader {
        self.sample.user_header()
    }

    /// The points, in the publisher's shared-memory segment (not a copy).
    pub fn points(&self) -> &[CloudPoint] {
        self.sample.payload()
    }
}

/// A subscriber together with the listener on its topic's event service.
struct TopicSubscriber<
    Payload: Debug + IceoryxSend + ?Sized + 'static,
    Header: Debug + ZeroCopySend,
> {
    subscriber: Subscriber<ipc::Service, Payload, Header>,
    listener: TopicListener,
    name: String,
}

impl<Payload: Debug + IceoryxSend + ?Sized + 'static, Header: Debug + ZeroCopySend>
    TopicSubscriber<Payload, Header>
{
    /// Subscribes to `name`, a topic that takes at most `max_subscribers`.
    fn create(
        node: &Node<ipc::Service>,
        name: String,
        max_subscribers: usize,
        buffer: Option<usize>,
        service: impl FnOnce(
            &Node<ipc::Service>,
            &str,
        ) -> Result<PubSubFactory<ipc::Service, Payload, Header>, IpcError>,
    ) -> Result<Self, IpcError> {
        // The listener exists before the subscriber does, so no notification
        // for a sample this subscriber can see is ever missed.
        let listener = TopicListener::create(node, &name)?;
        let factory = service(node, &name)?;
        let builder = factory.subscriber_builder();
        let builder = match buffer {
            Some(buffer) => builder.buffer_size(buffer),
            None => builder,
        };
        let subscriber = builder.create().map_err(|e| match e {
            SubscriberCreateError::ExceedsMaxSupportedSubscribers => IpcError {
                action: "create a subscriber",
                kind: "service",
                service: name.clone(),
                detail: format!(
                    "the topic takes at most {max_subscribers} subscribers at once and has \
                         that many: stop one (a slope-echo or slope-record left running?) or \
                         wait until one ends"
                ),
            },
            e => IpcError::new("create a subscriber", &name, e),
        })?;
        Ok(Self {
            subscriber,
            listener,
            name,
        })
    }
}

/// Subscribes to clouds and wakes on the cloud event.
pub struct CloudSubscriber {
    topic: TopicSubscriber<[CloudPoint], CloudHeader>,
}

impl CloudSubscriber {
    pub fn create(node: &Node<ipc::Service>, names: &ServiceNames) -> Result<Self, IpcError> {
        Ok(Self {
            topic: TopicSubscriber::create(
                node,
                names.cloud(),
                CLOUD_MAX_SUBSCRIBERS,
                Some(CLOUD_SUBSCRIBER_BUFFER),
                cloud_service,
            )?,
        })
    }

    /// A subscriber that holds up to [`CLOUD_RECORDER_BUFFER`] clouds
    /// unread (a recorder, which must lose none).
    pub fn create_deep(node: &Node<ipc::Service>, names: &ServiceNames) -> Result<Self, IpcError> {
        Ok(Self {
            topic: TopicSubscriber::create(
                node,
                names.cloud(),
                CLOUD_MAX_SUBSCRIBERS,
                Some(CLOUD_RECORDER_BUFFER),
                cloud_service,
            )?,
        })
    }

    pub fn listener(&self) -> &TopicListener {
        &self.topic.listener
    }

    pub fn service_name(&self) -> &str {
        &self.topic.name
    }

    pub fn receive(&self) -> Result<Option<CloudSample>, IpcError> {
        self.topic
            .subscriber
            .receive()
            .map(|s| s.map(|sample| CloudSample { sample }))
            .map_err(|e| IpcError::new("receive a cloud", &self.topic.name, e))
    }

    /// Receives everything waiting and returns the newest cloud, with how
    /// many older ones were skipped because a newer one had arrived.
    pub fn receive_newest(&self) -> Result<(Option<CloudSample>, u64), IpcError> {
        let mut newest = None;
        let mut skipped = 0;
        while let Some(sample) = self.receive()? {
            if newest.replace(sample).is_some() {
                skipped += 1;
            }
        }
        Ok((newest, skipped))
    }
}

/// Publishes slope estimates.
pub struct EstimatePublisher {
    service: EstimateService,
    publisher: Publisher<ipc::Service, SlopeEstimate, ()>,
    notifier: Notifier<ipc::Service>,
    name: String,
}

impl EstimatePublisher {
    pub fn create(node: &Node<ipc::Service>, names: &ServiceNames) -> Result<Self, IpcError> {
        let name = names.estimate();
        let service = estimate_service(node, &name)?;
        let publisher = service.publisher_builder().create().map_err(|e| {
            IpcError::new(
                "create a publisher (is another estimator already running?)",
                &name,
                e,
            )
        })?;
        let notifier = create_notifier(node, &name)?;
        Ok(Self {
            service,
            publisher,
            notifier,
            name,
        })
    }

    pub fn subscriber_count(&self) -> usize {
        self.service.dynamic_config().number_of_subscribers()
    }

    /// Stamps `publish_stamp_ns` and sends the estimate.
    pub fn publish(&self, estimate: &SlopeEstimate) -> Result<SlopeEstimate, IpcError> {
        let sample = self
            .publisher
            .loan_uninit()
            .map_err(|e| IpcError::new("loan a sample", &self.name, e))?;
        let mut message = *estimate;
        message.publish_stamp_ns = now_ns();
        sample
            .write_payload(message)
            .send()
            .map_err(|e| IpcError::new("send an estimate", &self.name, e))?;
        self.notifier
            .notify()
            .map_err(|e| IpcError::new("notify subscribers", &self.name, e))?;
        Ok(message)
    }
}

/// Subscribes to slope estimates and wakes on the estimate event.
pub struct EstimateSubscriber {
    topic: TopicSubscriber<SlopeEstimate, ()>,
}

impl EstimateSubscriber {
    pub fn create(node: &Node<ipc::Service>, names: &ServiceNames) -> Result<Self, IpcError> {
        Ok(Self {
            topic: TopicSubscriber::create(
                node,
                names.estimate(),
                ESTIMATE_MAX_SUBSCRIBERS,
                None,
                estimate_service,
            )?,
        })
    }

    pub fn listener(&self) -> &TopicListener {
        &self.topic.listener
    }

    pub fn receive(&self) -> Result<Option<SlopeEstimate>, IpcError> {
        self.topic
            .subscriber
            .receive()
            .map(|s| s.map(|sample| *sample.payload()))
            .map_err(|e| IpcError::new("receive an estimate", &self.topic.name, e))
    }
}

/// Publishes every surface of each frame on `<prefix>/surfaces`.
pub struct SurfacesPublisher {
    publisher: Publisher<ipc::Service, Surfaces, ()>,
    notifier: Notifier<ipc::Service>,
    name: String,
}

impl SurfacesPublisher {
    pub fn create(node: &Node<ipc::Service>, names: &ServiceNames) -> Result<Self, IpcError> {
        let name = names.surfaces();
        let publisher = surfaces_service(node, &name)?
            .publisher_builder()
            .create()
            .map_err(|e| {
                IpcError::new(
                    "create a publisher (is another estimator already running?)",
                    &name,
                    e,
                )
            })?;
        let notifier = create_notifier(node, &name)?;
        Ok(Self {
            publisher,
            notifier,
            name,
        })
    }

    /// Fills a loaned sample with `fill` (starting from
    /// `Surfaces::default()`), stamps `publish_stamp_ns` and sends it.
    pub fn publish(&self, fill: impl FnOnce(&mut Surfaces)) -> Result<(), IpcError> {
        let sample = self
            .publisher
            .loan_uninit()
            .map_err(|e| IpcError::new("loan a sample", &self.name, e))?;
        let mut sample = sample.write_payload(Surfaces::default());
        let message = sample.payload_mut();
        fill(message);
        message.publish_stamp_ns = now_ns();
        sample
            .send()
            .map_err(|e| IpcError::new("send the surfaces", &self.name, e))?;
        self.notifier
            .notify()
            .map_err(|e| IpcError::new("notify subscribers", &self.name, e))?;
        Ok(())
    }
}

/// Subscribes to the surfaces and wakes on their event.
pub struct SurfacesSubscriber {
    topic: TopicSubscriber<Surfaces, ()>,
}

impl SurfacesSubscriber {
    pub fn create(node: &Node<ipc::Service>, names: &ServiceNames) -> Result<Self, IpcError> {
        Ok(Self {
            topic: TopicSubscriber::create(
                node,
                names.surfaces(),
                SURFACES_MAX_SUBSCRIBERS,
                None,
                surfaces_service,
            )?,
        })
    }

    pub fn listener(&self) -> &TopicListener {
        &self.topic.listener
    }

    pub fn receive(&self) -> Result<Option<Surfaces>, IpcError> {
        self.topic
            .subscriber
            .receive()
            .map(|s| s.map(|sample| *sample.payload()))
            .map_err(|e| IpcError::new("receive the surfaces", &self.topic.name, e))
    }
}

/// Publishes a daemon's health reports on `<prefix>/health`.
pub struct HealthPublisher {
    publisher: Publisher<ipc::Service, Health, ()>,
    notifier: Notifier<ipc::Service>,
    name: String,
}

impl HealthPublisher {
    pub fn create(node: &Node<ipc::Service>, names: &ServiceNames) -> Result<Self, IpcError> {
        let name = names.health();
        let publisher = health_service(node, &name)?
            .publisher_builder()
            .create()
            .map_err(|e| IpcError::new("create a publisher", &name, e))?;
        let notifier = create_notifier(node, &name)?;
        Ok(Self {
            publisher,
            notifier,
            name,
        })
    }

    pub fn service_name(&self) -> &str {
        &self.name
    }

    /// Sends a report.
    pub fn publish(&self, health: &Health) -> Result<(), IpcError> {
        let sample = self
            .publisher
            .loan_uninit()
            .map_err(|e| IpcError::new("loan a sample", &self.name, e))?;
        sample
            .write_payload(*health)
            .send()
            .map_err(|e| IpcError::new("send a health report", &self.name, e))?;
        self.notifier
            .notify()
            .map_err(|e| IpcError::new("notify subscribers", &self.name, e))?;
        Ok(())
    }
}

/// Subscribes to health reports and wakes on the health event.
pub struct HealthSubscriber {
    topic: TopicSubscriber<Health, ()>,
}

impl HealthSubscriber {
    pub fn create(node: &Node<ipc::Service>, names: &ServiceNames) -> Result<Self, IpcError> {
        Ok(Self {
            topic: TopicSubscriber::create(
                node,
                names.health(),
                HEALTH_MAX_SUBSCRIBERS,
                None,
                health_service,
            )?,
        })
    }

    pub fn listener(&self) -> &TopicListener {
        &self.topic.listener
    }

    pub fn receive(&self) -> Result<Option<Health>, IpcError> {
        self.topic
            .subscriber
            .receive()
            .map(|s| s.map(|sample| *sample.payload()))
            .map_err(|e| IpcError::new("receive a health report", &self.topic.name, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One subscriber too many is refused with the topic's limit and what
    /// to do, not iceoryx2's bare `ExceedsMaxSupportedSubscribers`.
    #[test]
    fn one_subscriber_too_many_is_told_the_limit() {
        let prefix = format!("slope-test-ipc-limit-{}", std::process::id());
        let names = ServiceNames::new(prefix);
        let node = create_node(&format!("ipc-limit-{}", std::process::id())).expect("node");
        let subscribers: Vec<HealthSubscriber> = (0..HEALTH_MAX_SUBSCRIBERS)
            .map(|_| HealthSubscriber::create(&node, &names).expect("within the limit"))
            .collect();
        let err = match HealthSubscriber::create(&node, &names) {
            Ok(_) => panic!("{} subscribers accepted", subscribers.len() + 1),
            Err(err) => err.to_string(),
        };
        assert!(
            err.contains(&format!("at most {HEALTH_MAX_SUBSCRIBERS} subscribers")),
            "{err}"
        );
        assert!(err.contains("/health"), "{err}");
    }
}

//! Publish-to-receive latency of a full Kinect v2 cloud and of a 64-byte
//! message, over iceoryx2 and over a Unix domain socket, between two
//! processes. What it must show: the cloud over iceoryx2 within 2x of 64
//! bytes over iceoryx2, and at least 10x faster than the cloud over the
//! socket.
//!
//! Run: `cargo bench -p slope-sensor --bench ipc` (exit status 1 when a
//! ratio does not hold). `SLOPE_IPC_BENCH_MESSAGES` (default 2000) sets the
//! messages measured per case, after 200 of warm-up.
//!
//! How:
//! - The bench re-executes itself as the receiver (a second process, as a
//!   subscriber on the robot is), one per case, chosen by
//!   `SLOPE_IPC_BENCH_RECEIVE`. Service names and socket paths carry the pid,
//!   so a running stack is never touched.
//! - Every message starts with a 16-byte header: sequence number and the send
//!   time, `CLOCK_MONOTONIC` in ns (one clock for all processes on Linux;
//!   `Instant` cannot cross a process). The payload follows: 217088
//!   `CloudPoint`s (512 x 424 x 16 bytes, 3.3 MiB) or 4 (64 bytes). The
//!   socket carries the same bytes.
//! - iceoryx2: the sender loans a sample and projects the real Kinect v2
//!   frame into it in place (untimed: `benches/projection.rs` times that),
//!   then stamps and sends it. The stamp is taken when the message is
//!   complete, so latency is the transport's: for the socket, copying the
//!   bytes in and out of the kernel; for iceoryx2, handing over an offset.
//!   The receiver stamps once it holds the whole message (its own copy of
//!   every byte for the socket, the sample in shared memory for iceoryx2) and
//!   checks its length.
//! - Two ways to wait, both reported: `spin` busy-polls (iceoryx2
//!   `receive()`, a non-blocking socket read) and shows the transports alone;
//!   `block` sleeps (iceoryx2 `Listener` woken by a `Notifier` after each send,
//!   as `slope-estimator` does; a blocking socket read) and adds the
//!   scheduler's wake-up.
//! - Messages go out every 4 ms in every case, each built half a period
//!   ahead, so each finds the receiver idle (no queueing is measured) and
//!   the cases differ only in size. `lost` counts messages a receiver never
//!   saw (iceoryx2 replaces the oldest when a descheduled receiver falls two
//!   behind); latencies are of those received.

use std::io::{ErrorKind, Read, Write};
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::PathBuf;
use std::process::{Child, Command, ExitCode, Stdio};
use std::time::{Duration, Instant};

use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use iceoryx2::service::port_factory::event::PortFactory as EventFactory;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory as PubSubFactory;
use nix::time::{clock_gettime, ClockId};
use slope_ipc_types::CloudPoint;
use slope_sensor::ipc::{create_node, CLOUD_SUBSCRIBER_BUFFER};
use slope_sensor::projection::Projector;
use slope_sensor::recording::Recording;

/// Names the case a re-executed bench receives (the receiver role).
const RECEIVE_ENV: &str = "SLOPE_IPC_BENCH_RECEIVE";
/// The iceoryx2 service or socket path the receiver connects to.
const ENDPOINT_ENV: &str = "SLOPE_IPC_BENCH_ENDPOINT";
const MESSAGES_ENV: &str = "SLOPE_IPC_BENCH_MESSAGES";
const DEFAULT_MESSAGES: u64 = 2000;
const WARMUP: u64 = 200;
/// Time between messages, every case alike: long enough for the socket to
/// carry a cloud, so each message finds the receiver idle.
const PERIOD: Duration = Duration::from_millis(4);
/// Longest wait for a peer to connect or for the next message.
const PEER_TIMEOUT: Duration = Duration::from_secs(20);

const CLOUD_POINTS: usize = 512 * 424;
/// `CloudPoint`s in a 64-byte message.
const SMALL_POINTS: usize = 4;
/// Sequence number and send stamp, ahead of every payload.
type Stamp = [u64; 2];
const STAMP_BYTES: usize = 16;
const POINT_BYTES: usize = 16;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Transport {
    Iceoryx2,
    Uds,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Wake {
    Spin,
    Block,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Case {
    transport: Transport,
    points: usize,
    wake: Wake,
}

impl Case {
    fn all() -> Vec<Case> {
        let mut cases = Vec::new();
        for wake in [Wake::Spin, Wake::Block] {
            for transport in [Transport::Iceoryx2, Transport::Uds] {
                for points in [CLOUD_POINTS, SMALL_POINTS] {
                    cases.push(Case {
                        transport,
                        points,
                        wake,
                    });
                }
            }
        }
        cases
    }

    /// `iceoryx2-217088-spin`: also the receiver's role and a service name.
    fn label(&self) -> String {
        let transport = match self.transport {
            Transport::Iceoryx2 => "iceoryx2",
            Transport::Uds => "uds",
        };
        let wake = match self.wake {
            Wake::Spin => "spin",
            Wake::Block => "block",
        };
        format!("{transport}-{}-{wake}", self.points)
    }

    fn parse(label: &str) -> Option<Case> {
        Case::all().into_iter().find(|c| c.label() == label)
    }

    fn payload_bytes(&self) -> usize {
        self.points * POINT_BYTES
    }
}

/// `CLOCK_MONOTONIC` in ns, comparable between processes.
fn monotonic_ns() -> u64 {
    let now = clock_gettime(ClockId::CLOCK_MONOTONIC).expect("CLOCK_MONOTONIC is always there");
    Duration::from(now).as_nanos() as u64
}

fn messages() -> u64 {
    std::env::var(MESSAGES_ENV)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(DEFAULT_MESSAGES)
}

/// Latency percentiles of one case, ns, as the receiver reports them.
#[derive(Debug, Clone, Copy)]
struct Latency {
    median_ns: u64,
    p90_ns: u64,
    p99_ns: u64,
    max_ns: u64,
    lost: u64,
}

impl Latency {
    fn of(mut latencies_ns: Vec<u64>, lost: u64) -> Latency {
        latencies_ns.sort_unstable();
        let at = |q: f64| {
            let i = ((latencies_ns.len() as f64 * q) as usize).min(latencies_ns.len() - 1);
            latencies_ns[i]
        };
        Latency {
            median_ns: at(0.5),
            p90_ns: at(0.9),
            p99_ns: at(0.99),
            max_ns: at(1.0),
            lost,
        }
    }

    fn to_line(self) -> String {
        format!(
            "{} {} {} {} {}",
            self.median_ns, self.p90_ns, self.p99_ns, self.max_ns, self.lost
        )
    }

    fn from_line(line: &str) -> Option<Latency> {
        let v: Vec<u64> = line
            .split_whitespace()
            .map(str::parse)
            .collect::<Result<_, _>>()
            .ok()?;
        let [median_ns, p90_ns, p99_ns, max_ns, lost] = v[..] else {
            return None;
        };
        Some(Latency {
            median_ns,
            p90_ns,
            p99_ns,
            max_ns,
            lost,
        })
    }
}

/// Collects one case's latencies on the receiving side.
struct Tally {
    total: u64,
    latencies_ns: Vec<u64>,
    received: u64,
    last_seq: Option<u64>,
}

impl Tally {
    fn new(total: u64) -> Self {
        Self {
            total,
            latencies_ns: Vec::with_capacity(total as usize),
            received: 0,
            last_seq: None,
        }
    }

    fn record(&mut self, [seq, sent_ns]: Stamp, received_ns: u64) {
        self.received += 1;
        self.last_seq = Some(seq);
        if seq >= WARMUP {
            self.latencies_ns.push(received_ns.saturating_sub(sent_ns));
        }
    }

    fn done(&self) -> bool {
        self.last_seq.is_some_and(|s| s + 1 >= self.total)
    }

    fn finish(self) -> Latency {
        Latency::of(self.latencies_ns, self.total - self.received)
    }
}

type CloudService = PubSubFactory<ipc::Service, [CloudPoint], Stamp>;

/// Both ends open the service with the cloud topic's queue settings.
fn pubsub_service(node: &Node<ipc::Service>, name: &str) -> CloudService {
    node.service_builder(&ServiceName::new(name).expect("a valid service name"))
        .publish_subscribe::<[CloudPoint]>()
        .user_header::<Stamp>()
        .max_publishers(1)
        .max_subscribers(1)
        .subscriber_max_buffer_size(CLOUD_SUBSCRIBER_BUFFER)
        .subscriber_max_borrowed_samples(2)
        .history_size(0)
        .enable_safe_overflow(true)
        .open_or_create()
        .expect("the bench service opens")
}

fn event_service(node: &Node<ipc::Service>, name: &str) -> EventFactory<ipc::Service> {
    node.service_builder(&ServiceName::new(name).expect("a valid service name"))
        .event()
        .open_or_create()
        .expect("the bench event service opens")
}

// ---------------------------------------------------------------- receiver

fn receive(case: Case, endpoint: &str) -> Latency {
    let mut tally = Tally::new(WARMUP + messages());
    match case.transport {
        Transport::Iceoryx2 => receive_iceoryx2(case, endpoint, &mut tally),
        Transport::Uds => receive_uds(case, endpoint, &mut tally),
    }
    tally.finish()
}

fn receive_iceoryx2(case: Case, name: &str, tally: &mut Tally) {
    let node = create_node(&format!("slope-bench-ipc-rx-{}", std::process::id())).expect("node");
    // The listener before the subscriber: no notification is missed.
    let listener: Listener<ipc::Service> = event_service(&node, name)
        .listener_builder()
        .create()
        .expect("listener");
    let subscriber: Subscriber<ipc::Service, [CloudPoint], Stamp> = pubsub_service(&node, name)
        .subscriber_builder()
        .create()
        .expect("subscriber");
    let mut deadline = Instant::now() + PEER_TIMEOUT;
    while !tally.done() {
        if case.wake == Wake::Block {
            let timeout = deadline.saturating_duration_since(Instant::now());
            listener.timed_wait(|_| {}, timeout).expect("wait");
        }
        while let Some(sample) = subscriber.receive().expect("receive") {
            let received_ns = monotonic_ns();
            assert_eq!(sample.payload().len(), case.points, "payload length");
            tally.record(*sample.user_header(), received_ns);
            deadline = Instant::now() + PEER_TIMEOUT;
        }
        assert!(Instant::now() < deadline, "no message for {PEER_TIMEOUT:?}");
        std::hint::spin_loop();
    }
}

fn receive_uds(case: Case, path: &str, tally: &mut Tally) {
    let mut stream = UnixStream::connect(path).expect("connect to the bench socket");
    stream
        .set_nonblocking(case.wake == Wake::Spin)
        .expect("socket mode");
    stream
        .set_read_timeout(Some(PEER_TIMEOUT))
        .expect("read timeout");
    let mut message = vec![0u8; STAMP_BYTES + case.payload_bytes()];
    while !tally.done() {
        let mut filled = 0;
        let mut deadline = Instant::now() + PEER_TIMEOUT;
        while filled < message.len() {
            match stream.read(&mut message[filled..]) {
                Ok(0) => panic!("the sender closed the socket"),
                Ok(n) => {
                    filled += n;
                    deadline = Instant::now() + PEER_TIMEOUT;
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => {
                    std::hint::spin_loop();
                    assert!(Instant::now() < deadline, "no message for {PEER_TIMEOUT:?}");
                }
                Err(e) => panic!("read: {e}"),
            }
        }
        let received_ns = monotonic_ns();
        let word =
            |i: usize| u64::from_ne_bytes(message[i * 8..i * 8 + 8].try_into().expect("8 bytes"));
        tally.record([word(0), word(1)], received_ns);
    }
}

// ------------------------------------------------------------------ sender

/// The first frame of the real Kinect v2 recording (or the bundled one) and
/// its projector: what the sender writes.
fn kinect2_frame() -> (Projector, Vec<u16>) {
    let manifest = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let real = manifest.join("../../shared/data/kinect2-stairs-front");
    let dir = if real.is_dir() {
        real
    } else {
        manifest.join("../tests/recordings/ramp16")
    };
    let recording = Recording::open(&dir).expect("the bench recording opens");
    let first = recording.frames().first().expect("a frame");
    let depth = recording.read_depth(first).expect("the first frame reads");
    let projector = recording.projector();
    assert_eq!(projector.len(), CLOUD_POINTS, "a Kinect v2 frame");
    (projector, depth.data)
}

fn spawn_receiver(case: Case, endpoint: &str) -> Child {
    Command::new(std::env::current_exe().expect("the bench has a path"))
        .env(RECEIVE_ENV, case.label())
        .env(ENDPOINT_ENV, endpoint)
        .env(MESSAGES_ENV, messages().to_string())
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .spawn()
        .expect("start the receiver")
}

/// Sends a message every [`PERIOD`]: half a period ahead, `prepare` builds
/// it (untimed); at its time `send(seq, message)` stamps and sends it. The
/// half period after each send leaves the receiver the CPU to itself, as it
/// has with 64 bytes, even when both processes share one core.
fn paced<M>(mut prepare: impl FnMut() -> M, mut send: impl FnMut(u64, M)) {
    let sleep_until = |t: Instant| std::thread::sleep(t.saturating_duration_since(Instant::now()));
    let start = Instant::now() + PERIOD;
    for seq in 0..WARMUP + messages() {
        let slot = start + PERIOD * seq as u32;
        sleep_until(slot - PERIOD / 2);
        let message = prepare();
        sleep_until(slot);
        send(seq, message);
    }
}

fn send_iceoryx2(case: Case, frame: &(Projector, Vec<u16>)) -> Child {
    let pid = std::process::id();
    let name = format!("slope-bench-ipc-{pid}/{}", case.label());
    let node = create_node(&format!("slope-bench-ipc-tx-{pid}")).expect("node");
    let service = pubsub_service(&node, &name);
    let publisher: Publisher<ipc::Service, [CloudPoint], Stamp> = service
        .publisher_builder()
        .initial_max_slice_len(CLOUD_POINTS)
        .max_loaned_samples(1)
        .create()
        .expect("publisher");
    let notifier: Notifier<ipc::Service> = event_service(&node, &name)
        .notifier_builder()
        .create()
        .expect("notifier");
    let receiver = spawn_receiver(case, &name);
    let deadline = Instant::now() + PEER_TIMEOUT;
    while service.dynamic_config().number_of_subscribers() == 0 {
        assert!(Instant::now() < deadline, "the receiver did not subscribe");
        std::thread::sleep(Duration::from_millis(1));
    }
    let (projector, depth) = frame;
    paced(
        || {
            let sample = publisher.loan_slice_uninit(case.points).expect("loan");
            sample.write_from_fn(|i| projector.point(i, depth[i], 0))
        },
        |seq, mut sample| {
            *sample.user_header_mut() = [seq, monotonic_ns()];
            sample.send().expect("send");
            if case.wake == Wake::Block {
                notifier.notify().expect("notify");
            }
        },
    );
    receiver
}

fn send_uds(case: Case, frame: &(Projector, Vec<u16>)) -> Child {
    let path: PathBuf = std::env::temp_dir().join(format!(
        "slope-bench-ipc-{}-{}.sock",
        std::process::id(),
        case.label()
    ));
    let _ = std::fs::remove_file(&path);
    let listener = UnixListener::bind(&path).expect("bind the bench socket");
    listener.set_nonblocking(true).expect("non-blocking accept");
    let mut receiver = spawn_receiver(case, path.to_str().expect("a UTF-8 temp dir"));
    let deadline = Instant::now() + PEER_TIMEOUT;
    let mut stream = loop {
        match listener.accept() {
            Ok((stream, _)) => break stream,
            Err(e) if e.kind() == ErrorKind::WouldBlock => {
                let exited = receiver.try_wait().expect("try_wait");
                assert!(
                    exited.is_none() && Instant::now() < deadline,
                    "the receiver did not connect"
                );
                std::thread::sleep(Duration::from_millis(1));
            }
            Err(e) => panic!("accept: {e}"),
        }
    };
    let _ = std::fs::remove_file(&path);
    stream.set_nonblocking(false).expect("blocking writes");
    // The same bytes as over iceoryx2: the projected frame.
    let (projector, depth) = frame;
    let mut message = vec![0u8; STAMP_BYTES + case.payload_bytes()];
    for (i, bytes) in message[STAMP_BYTES..]
        .chunks_exact_mut(POINT_BYTES)
        .enumerate()
    {
        let p = projector.point(i, depth[i], 0);
        for (field, value) in bytes.chunks_exact_mut(4).zip([
            p.x_m.to_bits(),
            p.y_m.to_bits(),
            p.z_m.to_bits(),
            p.rgb,
        ]) {
            field.copy_from_slice(&value.to_ne_bytes());
        }
    }
    paced(
        || (),
        |seq, ()| {
            message[..8].copy_from_slice(&seq.to_ne_bytes());
            message[8..16].copy_from_slice(&monotonic_ns().to_ne_bytes());
            stream.write_all(&message).expect("write");
        },
    );
    receiver
}

fn measure(case: Case, frame: &(Projector, Vec<u16>)) -> Latency {
    let receiver = match case.transport {
        Transport::Iceoryx2 => send_iceoryx2(case, frame),
        Transport::Uds => send_uds(case, frame),
    };
    let output = receiver.wait_with_output().expect("the receiver ends");
    assert!(output.status.success(), "receiver {} failed", case.label());
    let line = String::from_utf8_lossy(&output.stdout);
    Latency::from_line(&line).unwrap_or_else(|| panic!("receiver printed {line:?}"))
}

fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|info| {
            info.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".to_string())
}

fn main() -> ExitCode {
    if let Ok(label) = std::env::var(RECEIVE_ENV) {
        let case = Case::parse(&label).expect("a known case");
        let endpoint = std::env::var(ENDPOINT_ENV).expect("the sender names the endpoint");
        println!("{}", receive(case, &endpoint).to_line());
        return ExitCode::SUCCESS;
    }
    let frame = kinect2_frame();
    let cpus = std::thread::available_parallelism().map_or(0, |n| n.get());
    println!(
        "ipc latency, publish to receive, {} messages per case after {WARMUP} warm-up; \
         {cpus} CPUs, {}",
        messages(),
        cpu_model()
    );
    println!(
        "{:<9} {:>10} {:<6} {:>10} {:>10} {:>10} {:>10} {:>5}",
        "transport", "payload B", "wait", "median µs", "p90 µs", "p99 µs", "max µs", "lost"
    );
    let mut results = Vec::new();
    for case in Case::all() {
        let latency = measure(case, &frame);
        let us = |ns: u64| ns as f64 / 1000.0;
        println!(
            "{:<9} {:>10} {:<6} {:>10.1} {:>10.1} {:>10.1} {:>10.1} {:>5}",
            format!("{:?}", case.transport).to_lowercase(),
            case.payload_bytes(),
            format!("{:?}", case.wake).to_lowercase(),
            us(latency.median_ns),
            us(latency.p90_ns),
            us(latency.p99_ns),
            us(latency.max_ns),
            latency.lost
        );
        results.push((case, latency));
    }
    let median = |transport, points, wake| {
        results
            .iter()
            .find(|(c, _)| c.transport == transport && c.points == points && c.wake == wake)
            .map_or(f64::NAN, |(_, l)| l.median_ns as f64)
    };
    let mut all_hold = true;
    for wake in [Wake::Spin, Wake::Block] {
        let cloud = median(Transport::Iceoryx2, CLOUD_POINTS, wake);
        let small = median(Transport::Iceoryx2, SMALL_POINTS, wake);
        let uds_cloud = median(Transport::Uds, CLOUD_POINTS, wake);
        let size_ratio = cloud / small;
        let uds_ratio = uds_cloud / cloud;
        let holds = [size_ratio <= 2.0, uds_ratio >= 10.0];
        all_hold &= holds.iter().all(|&h| h);
        let verdict = |h: bool| if h { "holds" } else { "FAILS" };
        println!(
            "{:<5} medians: iceoryx2 cloud / iceoryx2 64 B = {size_ratio:.2}x (<= 2x {}); \
             UDS cloud / iceoryx2 cloud = {uds_ratio:.0}x (>= 10x {})",
            format!("{wake:?}").to_lowercase(),
            verdict(holds[0]),
            verdict(holds[1])
        );
    }
    if all_hold {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}

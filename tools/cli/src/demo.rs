//! `slope-demo`: the whole chain on one machine. Starts `slope-estimator`
//! and `slope-replay` as child processes on a recording (the bundled 16°
//! ramp by default), subscribes to the estimates itself, prints each one
//! beside the recording's ground truth, and ends with a summary.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

use anyhow::{bail, Context};
use clap::Parser;
use nix::sys::signal::{kill, Signal};
use nix::unistd::Pid;
use slope_ipc_types::{
    EstimateStatus, ServiceNames, SlopeEstimate, SlopeMethod, DEFAULT_SERVICE_PREFIX,
};
use slope_sensor::ipc::{create_node, EstimateSubscriber};
use slope_sensor::publish::StopFlag;
use slope_sensor::recording::Recording;

use crate::cli::{node_name, prefix_arg, CommonArgs};
use crate::estimator::method_arg;
use crate::replay::positive_f64;

/// Environment variable naming the directory that holds the slope binaries
/// (default: the directory of the running executable).
pub const BIN_DIR_ENV: &str = "SLOPE_BIN_DIR";

impl DemoArgs {
    /// `--recording DIR` or `DIR`, else [`bundled_recording`].
    pub fn recording_dir(&self) -> PathBuf {
        self.recording
            .clone()
            .or_else(|| self.recording_positional.clone())
            .unwrap_or_else(bundled_recording)
    }
}

/// The bundled recording the demo plays when given none.
pub fn bundled_recording() -> PathBuf {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/recordings/ramp16");
    // Shown to the user: without the `..` when the checkout is still there.
    std::fs::canonicalize(&path).unwrap_or(path)
}

/// `--service-prefix` of the demo: it reads no config file.
const DEMO_PREFIX_HELP: &str = "Prefix of the iceoryx2 service names the demo's processes \
share; the demo adds -demo-<pid> to it, so that it never meets a running stack. Default: the \
environment variable SLOPE_SERVICE_PREFIX, else \"slope\"";

#[derive(Debug, Parser)]
#[command(
    mut_arg("service_prefix", |arg| arg.help(DEMO_PREFIX_HELP)),
    name = "slope-demo",
    version,
    about = "Run replay -> estimator -> subscriber on a recording and compare with its ground truth",
    long_about = "Starts slope-estimator and slope-replay as separate processes (talking over \
iceoryx2 shared memory under a private service prefix), subscribes to the slope estimates, \
prints each beside the recording's ground truth and ends with a summary. With no arguments it \
plays the bundled 16-degree ramp recording.\n\n\
SIGINT or SIGTERM (Ctrl-C) stops the estimator and the replay and prints the summary of what \
arrived so far, also before the first estimate; the exit status is then 0.",
    after_help = "Examples:
  slope-demo                                   # bundled 16° ramp, paper method
  slope-demo --method least-squares            # the baseline instead
  slope-demo ../shared/data/kinect2-stairs-front   # or --recording DIR
  slope-demo --rate 5                          # slower than the recorded 30 Hz"
)]
pub struct DemoArgs {
    /// Recording to play (default: the bundled 16° ramp in the source
    /// checkout's tests/recordings/ramp16; installed binaries need this flag
    /// or the RECORDING argument).
    #[arg(long)]
    pub recording: Option<PathBuf>,

    /// The same as --recording, given without the flag (as every other
    /// program takes a recording).
    #[arg(value_name = "RECORDING", conflicts_with = "recording")]
    pub recording_positional: Option<PathBuf>,

    /// Estimator method: paper, least-squares or tls.
    #[arg(long, value_parser = method_arg, default_value = "paper")]
    pub method: SlopeMethod,

    /// Replay at this many frames per second instead of the recorded rate.
    #[arg(long, value_parser = positive_f64)]
    pub rate: Option<f64>,

    /// Give up if the chain produces nothing for this many seconds.
    #[arg(
        long = "stall-timeout-s",
        alias = "stall-timeout",
        value_name = "S",
        allow_hyphen_values = true,
        default_value_t = 20.0,
        value_parser = positive_f64
    )]
    pub stall_timeout: f64,

    #[command(flatten)]
    pub common: CommonArgs,
}

/// Finds a sibling slope binary.
pub fn binary_path(name: &str) -> anyhow::Result<PathBuf> {
    let dir = match std::env::var_os(BIN_DIR_ENV) {
        Some(dir) => PathBuf::from(dir),
        None => std::env::current_exe()
            .context("cannot locate the running executable")?
            .parent()
            .map(Path::to_path_buf)
            .context("the running executable has no directory")?,
    };
    let path = dir.join(name);
    if !path.is_file() {
        bail!(
            "cannot find {} (build the workspace with `cargo build`, or set {BIN_DIR_ENV})",
            path.display()
        );
    }
    Ok(path)
}

/// A child process that is terminated when dropped.
struct ChildGuard {
    name: &'static str,
    child: Child,
}

impl ChildGuard {
    fn spawn(name: &'static str, command: &mut Command) -> anyhow::Result<Self> {
        let child = command
            .stdin(Stdio::null())
            .spawn()
            .with_context(|| format!("cannot start {name}"))?;
        Ok(Self { name, child })
    }

    fn try_wait(&mut self) -> anyhow::Result<Option<ExitStatus>> {
        self.child
            .try_wait()
            .with_context(|| format!("cannot query {}", self.name))
    }

    /// SIGTERM, then wait up to `grace`; SIGKILL after that.
    fn terminate(&mut self, grace: Duration) -> anyhow::Result<ExitStatus> {
        if let Some(status) = self.try_wait()? {
            return Ok(status);
        }
        let pid = Pid::from_raw(i32::try_from(self.child.id()).context("pid out of range")?);
        // The child may exit between the check and the signal; ESRCH is fine.
        let _ = kill(pid, Signal::SIGTERM);
        let deadline = Instant::now() + grace;
        while Instant::now() < deadline {
            if let Some(status) = self.try_wait()? {
                return Ok(status);
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        tracing::warn!(process = self.name, "did not stop on SIGTERM; killing it");
        self.child.kill().ok();
        self.child
            .wait()
            .with_context(|| format!("cannot wait for {}", self.name))
    }
}

impl Drop for ChildGuard {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            self.child.kill().ok();
            self.child.wait().ok();
        }
    }
}

/// What the demo saw.
#[derive(Debug, Clone, PartialEq)]
pub struct DemoSummary {
    /// Frames in the recording (the replay's children do not say how many
    /// they published: a stopped demo may have replayed fewer).
    pub recording_frames: usize,
    pub estimates: usize,
    pub ok: usize,
    pub median_slope_deg: Option<f64>,
    pub truth_deg: Option<f64>,
    pub abs_error_deg: Option<f64>,
    pub median_latency_ms: Option<f64>,
    pub dropped: u64,
}

pub fn median(values: &mut [f64]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    values.sort_by(f64::total_cmp);
    let mid = values.len() / 2;
    Some(if values.len().is_multiple_of(2) {
        (values[mid - 1] + values[mid]) / 2.0
    } else {
        values[mid]
    })
}

fn line_for(estimate: &SlopeEstimate, truth: Option<f64>) -> String {
    let head = format!("frame {:>5}", estimate.frame_index);
    let truth_text = truth.map_or("truth   -   ".to_string(), |t| format!("truth {t:6.2}°"));
    let latency = format!("latency {:6.1} ms", estimate.latency_ms());
    if estimate.status() == EstimateStatus::Ok {
        let error = truth.map_or(String::new(), |t| {
            format!("  error {:5.2}°", (estimate.slope_deg.abs() - t).abs())
        });
        // The tracked slope once the estimator follows one.
        let tracked = if estimate.has_tracked_slope() {
            format!("  tracked {:+7.2}°", estimate.tracked_slope_deg)
        } else {
            String::new()
        };
        format!(
            "{head}  slope {:+7.2}° ± {}{tracked}  {truth_text}{error}  {latency}",
            estimate.slope_deg,
            crate::echo::spread_text(estimate.slope_std_deg)
        )
    } else {
        format!(
            "{head}  {:<22} {truth_text}  {latency}",
            estimate.status().name()
        )
    }
}

pub fn run(args: &DemoArgs, stop: &StopFlag) -> anyhow::Result<DemoSummary> {
    let prefix = demo_prefix(args)?;
    let recording = DemoRecording::open(args.recording_dir())?;
    let names = ServiceNames::new(prefix.clone());
    let node = create_node(&node_name("slope-demo"))?;
    let subscriber = EstimateSubscriber::create(&node, &names)?;
    println!(
        "slope-demo: {} ({} frames) -> slope-replay -> slope-estimator --method {} -> here",
        recording.dir.display(),
        recording.frames,
        args.method.name()
    );
    let mut chain = Chain::spawn(args, &prefix, &recording.dir)?;
    let tally = watch(args, stop, &subscriber, &recording, &mut chain)?;
    chain.replay.terminate(Duration::from_secs(2))?;
    let status = chain.estimator.terminate(Duration::from_secs(3))?;
    if !status.success() && !stop.is_stopped() {
        bail!("slope-estimator did not exit cleanly ({status})");
    }
    let estimates = tally.estimates;
    let summary = tally.summary(&recording);
    print_summary(&summary);
    // Stopped before the first estimate (still waiting for the chain) is a
    // clean stop, not a failure.
    if estimates == 0 && !stop.is_stopped() {
        bail!("the estimator published no estimate");
    }
    Ok(summary)
}

/// The demo's service prefix: the given one with `-demo-<pid>`.
fn demo_prefix(args: &DemoArgs) -> anyhow::Result<String> {
    let prefix = format!(
        "{}-demo-{}",
        args.common.prefix_or(DEFAULT_SERVICE_PREFIX),
        std::process::id()
    );
    // The given prefix was checked alone; with -demo-<pid> it may no
    // longer fit.
    if let Err(reason) = prefix_arg(&prefix) {
        bail!("--service-prefix with the demo's -demo-<pid> added: {reason}");
    }
    Ok(prefix)
}

/// What the demo knows of its recording: where it is, its frames and
/// their ground truth.
struct DemoRecording {
    dir: PathBuf,
    truths: HashMap<u64, Option<f64>>,
    frames: usize,
    last_index: Option<u64>,
    truth_deg: Option<f64>,
}

impl DemoRecording {
    fn open(dir: PathBuf) -> anyhow::Result<Self> {
        let recording = Recording::open(&dir)
            .with_context(|| format!("cannot open the demo recording {}", dir.display()))?;
        let frames = recording.frames();
        Ok(Self {
            truths: frames
                .iter()
                .map(|f| (f.index, recording.truth_deg(f)))
                .collect(),
            frames: frames.len(),
            last_index: frames.last().map(|f| f.index),
            truth_deg: recording.meta().truth.slope_deg,
            dir,
        })
    }
}

/// The estimator and the replay, as child processes.
struct Chain {
    estimator: ChildGuard,
    replay: ChildGuard,
}

impl Chain {
    fn spawn(args: &DemoArgs, prefix: &str, recording_dir: &Path) -> anyhow::Result<Self> {
        let estimator_bin = binary_path("slope-estimator")?;
        let replay_bin = binary_path("slope-replay")?;
        let child_log = if args.common.log.verbose > 0 {
            "-v"
        } else {
            "-q"
        };
        let estimator = ChildGuard::spawn(
            "slope-estimator",
            Command::new(&estimator_bin)
                .args(["--method", args.method.name(), "--service-prefix", prefix])
                .arg(child_log),
        )?;
        let mut replay_cmd = Command::new(&replay_bin);
        replay_cmd
            .arg(recording_dir)
            .args(["--service-prefix", prefix, "--wait-subscribers", "1"])
            .args(["--wait-timeout-s", "30"])
            .arg(child_log);
        if let Some(rate) = args.rate {
            replay_cmd.args(["--rate", &rate.to_string()]);
        }
        let replay = ChildGuard::spawn("slope-replay", &mut replay_cmd)?;
        Ok(Self { estimator, replay })
    }
}

/// The estimates received so far.
#[derive(Default)]
struct Tally {
    estimates: usize,
    dropped: u64,
    slopes: Vec<f64>,
    latencies: Vec<f64>,
    errors: Vec<f64>,
}

impl Tally {
    /// Prints `estimate` beside its frame's truth and counts it.
    fn add(&mut self, estimate: &SlopeEstimate, recording: &DemoRecording) {
        self.estimates += 1;
        self.dropped = estimate.dropped_frames;
        let truth = recording
            .truths
            .get(&estimate.frame_index)
            .copied()
            .flatten();
        println!("{}", line_for(estimate, truth));
        self.latencies.push(estimate.latency_ms());
        if estimate.status() == EstimateStatus::Ok {
            self.slopes.push(estimate.slope_deg);
            if let Some(t) = truth {
                self.errors.push((estimate.slope_deg.abs() - t).abs());
            }
        }
    }

    fn summary(mut self, recording: &DemoRecording) -> DemoSummary {
        let median_slope_deg = median(&mut self.slopes);
        DemoSummary {
            recording_frames: recording.frames,
            estimates: self.estimates,
            ok: self.slopes.len(),
            median_slope_deg,
            truth_deg: recording.truth_deg,
            abs_error_deg: match (median_slope_deg, recording.truth_deg) {
                (Some(m), Some(t)) => Some((m.abs() - t).abs()),
                _ => median(&mut self.errors),
            },
            median_latency_ms: median(&mut self.latencies),
            dropped: self.dropped,
        }
    }
}

/// Receives and prints estimates until the recording's last frame's
/// arrives, the chain goes quiet after the replay ended, or `stop`; fails
/// when a child fails or nothing arrives for `--stall-timeout`.
fn watch(
    args: &DemoArgs,
    stop: &StopFlag,
    subscriber: &EstimateSubscriber,
    recording: &DemoRecording,
    chain: &mut Chain,
) -> anyhow::Result<Tally> {
    let stall = Duration::from_secs_f64(args.stall_timeout);
    let mut last_activity = Instant::now();
    let mut replay_done: Option<Instant> = None;
    let mut tally = Tally::default();
    let mut finished = false;
    while !finished && !stop.is_stopped() {
        subscriber.listener().wait(Duration::from_millis(100))?;
        while let Some(estimate) = subscriber.receive()? {
            last_activity = Instant::now();
            tally.add(&estimate, recording);
            finished |= Some(estimate.frame_index) == recording.last_index;
        }
        if replay_done.is_none() {
            if let Some(status) = chain.replay.try_wait()? {
                if !status.success() {
                    bail!("slope-replay failed ({status})");
                }
                replay_done = Some(Instant::now());
            }
        }
        if let Some(status) = chain.estimator.try_wait()? {
            bail!("slope-estimator exited early ({status})");
        }
        // After the replay ends, the last frame may have been superseded;
        // a quiet second means nothing more is coming.
        if replay_done.is_some_and(|t| t.elapsed() > Duration::from_secs(1))
            && last_activity.elapsed() > Duration::from_secs(1)
        {
            finished = true;
        }
        if last_activity.elapsed() > stall {
            bail!(
                "no estimate for {:.0} s; is the estimator keeping up? (try --rate 5 or -v)",
                stall.as_secs_f64()
            );
        }
    }
    Ok(tally)
}

fn print_summary(s: &DemoSummary) {
    let deg = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.2}°"));
    println!(
        "summary: {} estimates of a {}-frame recording ({} ok, {} dropped), median slope {}, truth {}, |error| {}, median latency {}",
        s.estimates,
        s.recording_frames,
        s.ok,
        s.dropped,
        deg(s.median_slope_deg),
        deg(s.truth_deg),
        deg(s.abs_error_deg),
        s.median_latency_ms
            .map_or("-".to_string(), |v| format!("{v:.1} ms")),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(&mut []), None);
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), Some(2.5));
    }

    #[test]
    fn the_recording_is_taken_with_or_without_the_flag() {
        let parse = |args: &[&str]| DemoArgs::try_parse_from(["slope-demo"].iter().chain(args));
        let positional = parse(&["tests/recordings/ramp16"]).expect("positional");
        assert_eq!(
            positional.recording_dir(),
            Path::new("tests/recordings/ramp16")
        );
        let flag = parse(&["--recording", "rec"]).expect("flag");
        assert_eq!(flag.recording_dir(), Path::new("rec"));
        assert_eq!(
            parse(&[]).expect("none").recording_dir(),
            bundled_recording()
        );
        assert!(parse(&["a", "--recording", "b"]).is_err(), "two recordings");
    }
}

//! `slope-echo`: prints every slope estimate, one line each, readable or JSON.

use std::io::Write;
use std::time::{Duration, Instant};

use clap::Parser;
use serde::Serialize;
use slope_ipc_types::{EstimateStatus, Health, SlopeEstimate, TimingStats};
use slope_sensor::ipc::{
    create_node, EstimateSubscriber, HealthSubscriber, SurfacesSubscriber, TopicListener,
};
use slope_sensor::publish::StopFlag;

use crate::cli::{
    max_frames_arg, node_name, wait_loop, CommonArgs, SilenceNote, CLIENT_PREFIX_HELP,
};
use crate::health::summary_line;
use crate::replay::positive_f64;
use crate::surfaces_json::{surfaces_text, SurfacesJson};

#[derive(Debug, Parser)]
#[command(
    // It has no --config: the daemons' file only.
    mut_arg("service_prefix", |arg| arg.help(CLIENT_PREFIX_HELP)),
    name = "slope-echo",
    version,
    about = "Print slope estimates from the estimate topic (or health reports), one line each",
    after_help = "Examples:
  slope-echo                            # readable lines until Ctrl-C
  slope-echo --json | jq .slope_deg     # one JSON object per line
  slope-echo --count 10 --timeout-s 5   # ten estimates, fail if they take over 5 s
  slope-echo --health                   # the daemons' health reports instead
  slope-echo --surfaces                 # every surface in view, the road marked

Readable lines show the slope ± its spread, the distance ahead, the tracked slope ± its \
spread (- without a track) and the confidence (with the reasons when below 1).

JSON fields: frame, timestamp_ns (capture, ns since the Unix epoch), publish_stamp_ns, \
source_stamp_ns, status, method, slope_deg, std_deg, distance_m, latency_ms (capture to \
publish), dropped_frames, ground_plane, inclined_plane ([a, b, c, d] or null), ground_inliers, \
inclined_inliers, ground_rms_m, inclined_rms_m, ground_area_m2, inclined_area_m2, \
ground_seen_to_m (how far ahead the ground was seen, metres: short of the sensor's range before a \
drop-off), samples, ground_from_mount, processing_ms, confidence, confidence_reasons (names), tracked_slope_deg, \
tracked_std_deg, tracked_frames, tracked_accepted.

Health lines (--health) show, per report: the daemon and its pid, uptime, rates in and out, \
frames in/out/dropped, reconnects, capture-to-publish latency and per-stage times as \
median/p95/max ms over the report's window, and the last error. With --json: component, pid, \
stamp_ns, uptime_ms, frames_in, frames_out, frames_dropped, reconnects, errors, rate_in_hz, \
rate_out_hz, window_ms, latency {median_ms, p95_ms, max_ms, count}, stages [{name, median_ms, \
p95_ms, max_ms, count}], last_error, last_error_stamp_ns.

Surfaces (--surfaces) show, per frame, its status and surface count, then one line per surface \
(the road marked ROAD): role, what it stands on, slope and heading (degrees), distance ahead \
near..far, lateral extent left..right (negative left), height above the ground lowest..highest \
(metres) and area (m²). With --json, one object per frame: frame, timestamp_ns, \
publish_stamp_ns, source_stamp_ns, status, road (index or null), ground_from_mount, up, \
forward, ground_plane, corridor_half_width_m, look_ahead_m, surfaces [{role, support, \
supported_by, road, inliers, segments, joins_ground, in_corridor, measurable, slope_deg, \
heading_deg, distance_m, far_m, left_m, right_m, lowest_m, highest_m, area_m2, rms_m, \
noise_ratio, plane, outline}] (largest first; NaN as null)."
)]
pub struct EchoArgs {
    /// One JSON object per line instead of readable text.
    #[arg(long)]
    pub json: bool,

    /// Print the daemons' health reports (topic PREFIX/health) instead of
    /// estimates; --count and --timeout-s then count reports.
    #[arg(long, conflicts_with = "surfaces")]
    pub health: bool,

    /// Print every surface of each frame (topic PREFIX/surfaces) instead of
    /// estimates: a header line per frame, then one line per surface;
    /// --count and --timeout-s then count frames.
    #[arg(long)]
    pub surfaces: bool,

    /// Exit (status 0) after this many messages (at least 1).
    #[arg(long, value_parser = max_frames_arg)]
    pub count: Option<u64>,

    /// Exit after this many seconds: status 0 when no --count was given,
    /// non-zero when fewer than --count estimates arrived.
    #[arg(
        long = "timeout-s",
        alias = "timeout",
        value_name = "S",
        allow_hyphen_values = true,
        value_parser = positive_f64
    )]
    pub timeout: Option<f64>,

    #[command(flatten)]
    pub common: CommonArgs,
}

/// The JSON form of one estimate (`slope-echo --json`): every field of the
/// message; NaN values and absent planes are `null`.
#[derive(Debug, Serialize)]
pub struct EstimateJson {
    pub frame: u64,
    pub timestamp_ns: u64,
    pub publish_stamp_ns: u64,
    pub source_stamp_ns: u64,
    pub status: &'static str,
    pub method: &'static str,
    pub slope_deg: Option<f64>,
    pub std_deg: Option<f64>,
    pub distance_m: Option<f64>,
    pub latency_ms: f64,
    pub dropped_frames: u64,
    pub ground_plane: Option<[f64; 4]>,
    pub inclined_plane: Option<[f64; 4]>,
    pub ground_inliers: u32,
    pub inclined_inliers: u32,
    pub ground_rms_m: Option<f64>,
    pub inclined_rms_m: Option<f64>,
    pub ground_area_m2: Option<f64>,
    pub inclined_area_m2: Option<f64>,
    pub ground_seen_to_m: Option<f64>,
    pub samples: u32,
    pub ground_from_mount: bool,
    pub processing_ms: f64,
    pub confidence: f64,
    pub confidence_reasons: Vec<std::borrow::Cow<'static, str>>,
    pub tracked_slope_deg: Option<f64>,
    pub tracked_std_deg: Option<f64>,
    pub tracked_frames: u32,
    pub tracked_accepted: bool,
}

fn finite(value: f64) -> Option<f64> {
    value.is_finite().then_some(value)
}

/// How far ahead the ground was seen, `None` without a measured ground (NaN)
/// or from an estimator older than the field (0).
fn seen_to_m(e: &SlopeEstimate) -> Option<f64> {
    finite(f64::from(e.ground_seen_to_m)).filter(|&m| m > 0.0)
}

/// A plane of the message, `None` when absent (all zero).
fn plane(coefficients: [f64; 4]) -> Option<[f64; 4]> {
    (coefficients != [0.0; 4]).then_some(coefficients)
}

impl From<&SlopeEstimate> for EstimateJson {
    fn from(e: &SlopeEstimate) -> Self {
        Self {
            frame: e.frame_index,
            timestamp_ns: e.capture_stamp_ns,
            publish_stamp_ns: e.publish_stamp_ns,
            source_stamp_ns: e.source_stamp_ns,
            status: e.status().name(),
            method: e.method().map_or("unknown", |m| m.name()),
            slope_deg: finite(e.slope_deg),
            std_deg: finite(e.slope_std_deg),
            distance_m: finite(e.distance_m),
            latency_ms: e.latency_ms(),
            dropped_frames: e.dropped_frames,
            ground_plane: plane(e.ground_plane),
            inclined_plane: plane(e.inclined_plane),
            ground_inliers: e.ground_inliers,
            inclined_inliers: e.inclined_inliers,
            ground_rms_m: finite(e.ground_rms_m),
            inclined_rms_m: finite(e.inclined_rms_m),
            ground_area_m2: finite(e.ground_area_m2),
            inclined_area_m2: finite(e.inclined_area_m2),
            ground_seen_to_m: seen_to_m(e),
            samples: e.samples,
            ground_from_mount: e.ground_from_mount != 0,
            processing_ms: e.processing_us as f64 / 1000.0,
            confidence: e.confidence,
            confidence_reasons: e.confidence_reason_names().collect(),
            tracked_slope_deg: finite(e.tracked_slope_deg),
            tracked_std_deg: finite(e.tracked_std_deg),
            tracked_frames: e.tracked_frames,
            tracked_accepted: e.tracked_accepted != 0,
        }
    }
}

/// The readable line for one estimate.
pub fn format_line(e: &SlopeEstimate) -> String {
    let status = e.status();
    let head = format!("frame {:>6}", e.frame_index);
    let tail = format!(
        "latency {:>6.1} ms  dropped {}",
        e.latency_ms(),
        e.dropped_frames
    );
    if status == EstimateStatus::Ok {
        let distance = if e.distance_m.is_finite() {
            format!("{:5.2} m", e.distance_m)
        } else {
            "  -   ".to_string()
        };
        format!(
            "{head}  slope {:+7.2}° ± {}  ahead {distance}  {}  {}  {tail}",
            e.slope_deg,
            spread_text(e.slope_std_deg),
            tracked_text(e),
            confidence_text(e)
        )
    } else if e.ground_plane != [0.0; 4] {
        // No slope, but the ground was measured: flat floor ahead, as far
        // as it was seen (a drop-off shows as a short reach).
        let mut ground = format!("ground {:.2} m below", e.ground_plane[3]);
        if let Some(seen) = seen_to_m(e) {
            ground.push_str(&format!(", seen to {seen:.2} m ahead"));
        }
        format!("{head}  {:<30} {ground}  {tail}", status.name())
    } else {
        format!("{head}  {:<30} {tail}", status.name())
    }
}

/// The spread as `" 0.20°"`, or `"   - "` when there is none (the
/// baselines' single fit).
pub fn spread_text(std_deg: f64) -> String {
    if std_deg.is_finite() {
        format!("{std_deg:5.2}°")
    } else {
        "   - ".to_string()
    }
}

/// `confidence 0.62 (few_points, rough_plane)`: the reasons only when the
/// confidence is below 1.
fn confidence_text(e: &SlopeEstimate) -> String {
    let text = format!("confidence {:4.2}", e.confidence);
    let reasons: Vec<_> = e.confidence_reason_names().collect();
    if e.confidence < 1.0 && !reasons.is_empty() {
        format!("{text} ({})", reasons.join(", "))
    } else {
        text
    }
}

/// `tracked +16.00° ±  0.05°`, or `tracked -` without a tracked slope.
fn tracked_text(e: &SlopeEstimate) -> String {
    if !e.has_tracked_slope() {
        return "tracked -".to_string();
    }
    let spread = if e.tracked_std_deg.is_finite() {
        format!(" ± {:5.2}°", e.tracked_std_deg)
    } else {
        String::new()
    };
    format!("tracked {:+7.2}°{spread}", e.tracked_slope_deg)
}

pub fn run(args: &EchoArgs, stop: &StopFlag) -> anyhow::Result<u64> {
    let names = args.common.service_names(stop)?;
    let node = create_node(&node_name("slope-echo"))?;
    if args.health {
        let subscriber = HealthSubscriber::create(&node, &names)?;
        let topic = Topic {
            service: names.health(),
            what: "health report",
            publisher: "slope-estimator or slope-capture",
        };
        tracing::info!(service = %topic.service, "subscribed to health reports");
        return echo(args, stop, subscriber.listener(), &topic, || {
            let Some(health) = subscriber.receive()? else {
                return Ok(None);
            };
            Ok(Some(if args.json {
                serde_json::to_string(&HealthJson::from(&health))?
            } else {
                summary_line(&health)
            }))
        });
    }
    if args.surfaces {
        let subscriber = SurfacesSubscriber::create(&node, &names)?;
        let topic = Topic {
            service: names.surfaces(),
            what: "surfaces message",
            publisher: "slope-estimator",
        };
        tracing::info!(service = %topic.service, "subscribed to surfaces");
        return echo(args, stop, subscriber.listener(), &topic, || {
            let Some(surfaces) = subscriber.receive()? else {
                return Ok(None);
            };
            Ok(Some(if args.json {
                serde_json::to_string(&SurfacesJson::from(&surfaces))?
            } else {
                surfaces_text(&surfaces)
            }))
        });
    }
    let subscriber = EstimateSubscriber::create(&node, &names)?;
    let topic = Topic {
        service: names.estimate(),
        what: "estimate",
        publisher: "slope-estimator",
    };
    tracing::info!(service = %topic.service, "subscribed to estimates");
    echo(args, stop, subscriber.listener(), &topic, || {
        let Some(estimate) = subscriber.receive()? else {
            return Ok(None);
        };
        Ok(Some(if args.json {
            serde_json::to_string(&EstimateJson::from(&estimate))?
        } else {
            format_line(&estimate)
        }))
    })
}

/// The topic `slope-echo` prints.
struct Topic {
    service: String,
    /// What arrives on it, singular ("estimate").
    what: &'static str,
    /// Which program publishes it.
    publisher: &'static str,
}

/// Prints the lines `next` makes (`None`: nothing waiting) until --count,
/// --timeout-s or a stop; returns how many were printed.
fn echo(
    args: &EchoArgs,
    stop: &StopFlag,
    listener: &TopicListener,
    topic: &Topic,
    mut next: impl FnMut() -> anyhow::Result<Option<String>>,
) -> anyhow::Result<u64> {
    let deadline = args
        .timeout
        .map(|s| Instant::now() + Duration::from_secs_f64(s));
    let mut received = 0u64;
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    let count_reached = |received: u64| args.count.is_some_and(|c| received >= c);
    let mut silence = SilenceNote::new(topic.what, &topic.service, topic.publisher);
    let result = wait_loop(listener, stop, || {
        silence.tick();
        while !count_reached(received) {
            let Some(line) = next()? else {
                break;
            };
            silence.heard();
            writeln!(out, "{line}").and_then(|()| out.flush())?;
            received += 1;
        }
        let timed_out = deadline.is_some_and(|d| Instant::now() >= d);
        Ok(!count_reached(received) && !timed_out)
    });
    if let Err(err) = result {
        // A reader that went away (`slope-echo --json | head`) is not an error.
        let closed_pipe = err
            .downcast_ref::<std::io::Error>()
            .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe);
        if closed_pipe {
            return Ok(received);
        }
        return Err(err.context("slope-echo stopped"));
    }
    if let Some(count) = args.count {
        if received < count && !stop.is_stopped() {
            anyhow::bail!(
                "only {received} of {count} {}s arrived on '{}' within {} s",
                topic.what,
                topic.service,
                args.timeout.unwrap_or_default()
            );
        }
    }
    Ok(received)
}

/// Timing figures in JSON: `null` where there were no frames.
#[derive(Debug, Serialize)]
pub struct TimingJson {
    pub median_ms: Option<f64>,
    pub p95_ms: Option<f64>,
    pub max_ms: Option<f64>,
    pub count: u64,
}

impl From<&TimingStats> for TimingJson {
    fn from(t: &TimingStats) -> Self {
        Self {
            median_ms: finite(t.median_ms),
            p95_ms: finite(t.p95_ms),
            max_ms: finite(t.max_ms),
            count: t.count,
        }
    }
}

/// One stage's timing in JSON.
#[derive(Debug, Serialize)]
pub struct StageJson {
    pub name: String,
    #[serde(flatten)]
    pub timing: TimingJson,
}

/// The JSON form of a health report (`slope-echo --health --json`).
#[derive(Debug, Serialize)]
pub struct HealthJson {
    pub component: &'static str,
    pub pid: u32,
    pub stamp_ns: u64,
    pub uptime_ms: u64,
    pub frames_in: u64,
    pub frames_out: u64,
    pub frames_dropped: u64,
    pub reconnects: u64,
    pub errors: u64,
    pub rate_in_hz: f64,
    pub rate_out_hz: f64,
    pub window_ms: u64,
    pub latency: TimingJson,
    pub stages: Vec<StageJson>,
    pub last_error: Option<String>,
    pub last_error_stamp_ns: Option<u64>,
}

impl From<&Health> for HealthJson {
    fn from(h: &Health) -> Self {
        let error = h.last_error();
        Self {
            component: h.component().map_or("unknown", |c| c.name()),
            pid: h.pid,
            stamp_ns: h.stamp_ns,
            uptime_ms: h.uptime_ms,
            frames_in: h.frames_in,
            frames_out: h.frames_out,
            frames_dropped: h.frames_dropped,
            reconnects: h.reconnects,
            errors: h.errors,
            rate_in_hz: h.rate_in_hz,
            rate_out_hz: h.rate_out_hz,
            window_ms: h.window_ms,
            latency: TimingJson::from(&h.latency),
            stages: h
                .stages()
                .iter()
                .map(|s| StageJson {
                    name: s.name().to_string(),
                    timing: TimingJson::from(&s.timing),
                })
                .collect(),
            last_error: (!error.is_empty()).then(|| error.to_string()),
            last_error_stamp_ns: (h.last_error_stamp_ns != 0).then_some(h.last_error_stamp_ns),
        }
    }
}

#[cfg(test)]
mod tests {
    use slope_ipc_types::{confidence, SlopeMethod};

    use super::*;

    fn ok_estimate() -> SlopeEstimate {
        SlopeEstimate {
            frame_index: 12,
            capture_stamp_ns: 1_000_000_000,
            publish_stamp_ns: 1_020_000_000,
            status: EstimateStatus::Ok as u32,
            method: SlopeMethod::Paper as u32,
            slope_deg: 16.02,
            slope_std_deg: 0.2,
            distance_m: 1.52,
            ground_plane: [0.0, -0.94, 0.34, 0.5],
            inclined_plane: [0.0, -0.7, -0.7, 1.2],
            ground_inliers: 40_000,
            inclined_inliers: 9_000,
            ground_rms_m: 0.002,
            inclined_rms_m: 0.003,
            ground_area_m2: 3.5,
            inclined_area_m2: 0.8,
            ground_seen_to_m: 0.0,
            samples: 1000,
            processing_us: 25_000,
            confidence: 0.62,
            confidence_reasons: confidence::FEW_POINTS | confidence::ROUGH_PLANE,
            tracked_slope_deg: 16.0,
            tracked_std_deg: 0.05,
            tracked_frames: 9,
            tracked_accepted: 1,
            ..SlopeEstimate::default()
        }
    }

    #[test]
    fn the_line_shows_confidence_reasons_and_the_tracked_slope() {
        let line = format_line(&ok_estimate());
        assert!(line.contains("slope  +16.02° ±  0.20°"), "{line}");
        assert!(line.contains("tracked  +16.00° ±  0.05°"), "{line}");
        assert!(
            line.contains("confidence 0.62 (few_points, rough_plane)"),
            "{line}"
        );
        let sure = SlopeEstimate {
            confidence: 1.0,
            confidence_reasons: 0,
            tracked_slope_deg: f64::NAN,
            tracked_std_deg: f64::NAN,
            ..ok_estimate()
        };
        let line = format_line(&sure);
        assert!(
            line.contains("tracked -  confidence 1.00  latency"),
            "{line}"
        );
    }

    /// No inclined plane but a measured floor: the line says where it is.
    #[test]
    fn a_flat_floor_is_shown_with_its_distance() {
        let flat = SlopeEstimate {
            status: EstimateStatus::NoInclinedPlane as u32,
            ground_plane: [0.0, -0.9, -0.42, 0.61],
            ..SlopeEstimate::default()
        };
        let line = format_line(&flat);
        assert!(line.contains("no_inclined_plane"), "{line}");
        assert!(line.contains("ground 0.61 m below"), "{line}");
        assert!(!line.contains("seen to"), "{line}");
        let edge = SlopeEstimate {
            ground_seen_to_m: 1.84,
            ..flat
        };
        let line = format_line(&edge);
        assert!(
            line.contains("ground 0.61 m below, seen to 1.84 m ahead"),
            "{line}"
        );
        let nothing = SlopeEstimate {
            status: EstimateStatus::NoInclinedPlane as u32,
            ..SlopeEstimate::default()
        };
        assert!(!format_line(&nothing).contains("ground"));
    }

    #[test]
    fn json_has_every_field_and_null_for_what_is_absent() {
        let value = serde_json::to_value(EstimateJson::from(&ok_estimate())).unwrap();
        assert_eq!(value["confidence"], 0.62);
        assert_eq!(
            value["confidence_reasons"],
            serde_json::json!(["few_points", "rough_plane"])
        );
        assert_eq!(
            value["inclined_plane"],
            serde_json::json!([0.0, -0.7, -0.7, 1.2])
        );
        assert_eq!(value["ground_rms_m"], 0.002);
        assert_eq!(value["inclined_area_m2"], 0.8);
        assert_eq!(value["tracked_slope_deg"], 16.0);
        assert_eq!(value["tracked_frames"], 9);
        assert_eq!(value["tracked_accepted"], true);
        assert_eq!(value["publish_stamp_ns"], 1_020_000_000u64);
        // 0 is what an estimator older than the field sends: unknown.
        assert_eq!(value["ground_seen_to_m"], serde_json::Value::Null);
        let seen = SlopeEstimate {
            ground_seen_to_m: 3.5,
            ..ok_estimate()
        };
        let seen = serde_json::to_value(EstimateJson::from(&seen)).unwrap();
        assert_eq!(seen["ground_seen_to_m"], 3.5);
        assert_eq!(value.as_object().unwrap().len(), 29);

        let failed = SlopeEstimate {
            status: EstimateStatus::NoInclinedPlane as u32,
            ..SlopeEstimate::default()
        };
        let value = serde_json::to_value(EstimateJson::from(&failed)).unwrap();
        for key in [
            "slope_deg",
            "ground_plane",
            "inclined_plane",
            "ground_rms_m",
            "inclined_area_m2",
            "tracked_slope_deg",
            "tracked_std_deg",
        ] {
            assert!(value[key].is_null(), "{key}: {value}");
        }
        assert_eq!(value["confidence_reasons"], serde_json::json!([]));
        assert_eq!(value["tracked_accepted"], false);
    }

    #[test]
    fn health_json_has_every_field_and_null_for_no_frames() {
        let mut h = Health::new(slope_ipc_types::HealthComponent::Estimator);
        h.frames_in = 5;
        h.push_stage("total", TimingStats::of(&mut [2.0, 4.0]));
        h.push_stage("outlier", TimingStats::EMPTY);
        let value = serde_json::to_value(HealthJson::from(&h)).unwrap();
        assert_eq!(value.as_object().unwrap().len(), 16);
        assert_eq!(value["component"], "estimator");
        assert_eq!(value["frames_in"], 5);
        assert_eq!(value["stages"][0]["name"], "total");
        assert_eq!(value["stages"][0]["max_ms"], 4.0);
        assert!(value["stages"][1]["median_ms"].is_null());
        assert!(value["latency"]["p95_ms"].is_null());
        assert!(value["last_error"].is_null());
        h.set_last_error("no clouds", 7);
        let value = serde_json::to_value(HealthJson::from(&h)).unwrap();
        assert_eq!(value["last_error"], "no clouds");
        assert_eq!(value["last_error_stamp_ns"], 7);
    }
}

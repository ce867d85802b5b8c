//! [`Kinect2Source`]: the Kinect v2 as a [`FrameSource`], feeding the same
//! publishing code as a recording.
//!
//! It owns the whole device life cycle: waiting for a device to appear,
//! starting the streams, undistorting and registering each frame set,
//! skipping (and counting) frames that libfreenect2 flags as bad, and, when
//! frames stop coming (a pulled cable, a USB reset), dropping the device and
//! reopening the same serial with exponential backoff, without ending the
//! stream. Every wait honours the [`StopFlag`], so SIGINT/SIGTERM stop it
//! within one wait slice (200 ms): opening and starting a device, which
//! block inside libfreenect2 for seconds, run on a thread of their own
//! ([`run_interruptible`]).
//!
//! A depth pipeline that cannot work (OpenCL/CUDA that failed to initialise:
//! colour flows, depth never comes) is an error naming the pipeline and the
//! `cpu` fallback ([`Kinect2Error::DepthPipelineFailed`]), not a reason to
//! reconnect: see [`MissingDepthDetector`].

use std::time::{Duration, Instant};

use slope_ipc_types::CloudSource;

use super::choice::{DeviceSelector, Pipeline};
use super::clock::DeviceClock;
use super::convert::{unmirror_color, unmirror_depth, unmirrored_intrinsics, DEPTH_UNIT_M};
use super::device::{Context, Device, FrameSet, Streams};
use super::error::Kinect2Error;
use super::frame::{check_layout, FrameFormat, FrameView};
use super::log::depth_pipeline_errors;
use super::options::{CaptureStats, Kinect2Options, SENSOR_NAME};
use super::params::{IrParams, COLOR_HEIGHT, COLOR_WIDTH, DEPTH_HEIGHT, DEPTH_PIXELS, DEPTH_WIDTH};
use super::registration::Registration;
use crate::interruptible::run_interruptible;
use crate::missing_depth::MissingDepthDetector;
use crate::publish::StopFlag;
use crate::recording::ColorImage;
use crate::source::{FrameSource, SourceError, SourceFrame, SourceInfo};

/// Slice of every blocking wait, so that a stop request is seen quickly.
pub const WAIT_SLICE: Duration = Duration::from_millis(200);

/// Called about every [`WAIT_SLICE`] while the source waits (for a device,
/// for frames, before a reconnect) and after every frame, with the counters
/// so far: where a daemon pings its watchdog.
pub type WaitHook = Box<dyn FnMut(&CaptureStats)>;
/// How often the counters are logged while streaming.
const REPORT_EVERY: Duration = Duration::from_secs(60);

/// A started device with what it needs to convert frames.
struct Running {
    device: Device,
    registration: Registration,
    last_frame: Instant,
}

/// The Kinect v2 as a frame source.
pub struct Kinect2Source {
    options: Kinect2Options,
    context: Context,
    running: Option<Running>,
    /// The serial opened first; reconnects reopen exactly this device.
    serial: String,
    ir: IrParams,
    info: SourceInfo,
    stop: StopFlag,
    stats: CaptureStats,
    next_index: u64,
    clock: DeviceClock,
    /// When the last frame set arrived (spans reconnects).
    last_frame_at: Option<Instant>,
    /// The device was reopened since the last frame set.
    reopened: bool,
    backoff: Duration,
    last_report: Instant,
    undistorted: Vec<f32>,
    registered: Vec<u32>,
    missing_depth: MissingDepthDetector,
    on_wait: WaitHook,
}

impl std::fmt::Debug for Kinect2Source {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Kinect2Source")
            .field("serial", &self.serial)
            .field("info", &self.info)
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

impl Kinect2Source {
    /// Opens and starts the device. With `wait_for_device`, retries (with
    /// backoff) until one appears; `Ok(None)` when `stop` was set first.
    /// Without it, fails at once when no Kinect v2 is connected.
    pub fn open(options: Kinect2Options, stop: StopFlag) -> Result<Option<Self>, Kinect2Error> {
        Self::open_watched(options, stop, Box::new(|_| {}))
    }

    /// [`Kinect2Source::open`], calling `on_wait` about every 200 ms while
    /// it waits (and later while streaming, see [`WaitHook`]).
    pub fn open_watched(
        options: Kinect2Options,
        stop: StopFlag,
        mut on_wait: WaitHook,
    ) -> Result<Option<Self>, Kinect2Error> {
        let context = Context::new()?;
        let mut stats = CaptureStats::default();
        let Some(running) = start_waiting(&context, &options, &stop, &mut on_wait, &mut stats)?
        else {
            return Ok(None);
        };
        let serial = running.device.serial().to_string();
        let ir = *running.registration.ir_params();
        let info = SourceInfo {
            width: DEPTH_WIDTH as u32,
            height: DEPTH_HEIGHT as u32,
            intrinsics: unmirrored_intrinsics(&ir, DEPTH_WIDTH as u32),
            unit_m: DEPTH_UNIT_M,
            mount: options.mount,
            source: CloudSource::Camera,
            has_color: options.color,
            sensor: SENSOR_NAME.to_string(),
        };
        tracing::info!(
            serial,
            pipeline = %running.device.pipeline(),
            fx = info.intrinsics.fx,
            fy = info.intrinsics.fy,
            cx = info.intrinsics.cx,
            cy = info.intrinsics.cy,
            color = options.color,
            "Kinect v2 streaming"
        );
        let missing_depth = MissingDepthDetector::new(options.frame_timeout.mul_f64(2.0 / 3.0));
        Ok(Some(Self {
            backoff: options.min_backoff,
            options,
            context,
            running: Some(running),
            serial,
            ir,
            info,
            stop,
            stats,
            next_index: 0,
            clock: DeviceClock::default(),
            last_frame_at: None,
            reopened: false,
            last_report: Instant::now(),
            undistorted: vec![0.0; DEPTH_PIXELS],
            registered: vec![0; DEPTH_PIXELS],
            missing_depth,
            on_wait,
        }))
    }

    /// The serial of the device being streamed.
    pub fn serial(&self) -> &str {
        &self.serial
    }

    /// libfreenect2's IR camera parameters (mirrored, +0.5 convention).
    pub fn ir_params(&self) -> &IrParams {
        &self.ir
    }

    pub fn stats(&self) -> CaptureStats {
        self.stats
    }

    /// True while a device is open and streaming.
    pub fn is_connected(&self) -> bool {
        self.running.is_some()
    }

    /// Stops the streams and closes the device now (also done on drop).
    pub fn close(&mut self) {
        if let Some(mut running) = self.running.take() {
            if let Err(err) = running.device.stop() {
                tracing::warn!(error = %err, "stopping the Kinect v2 failed");
            }
            // Dropping the device closes it, then frees its listener.
        }
    }

    /// Tries to reopen the device after a loss, waiting the current backoff
    /// first. Returns false if stopped; fails on errors that retrying
    /// cannot cure (see [`Kinect2Error::is_retryable`]).
    fn reconnect(&mut self) -> Result<bool, Kinect2Error> {
        if !sleep_watched(&self.stop, self.backoff, &mut self.on_wait, &self.stats) {
            return Ok(false);
        }
        let selector = DeviceSelector::Serial(self.serial.clone());
        let Some(started) = start_interruptible(
            &self.context,
            &self.options,
            &selector,
            &self.stop,
            &mut self.on_wait,
            &self.stats,
        )?
        else {
            return Ok(false);
        };
        match started {
            Ok(running) => {
                let ir = *running.registration.ir_params();
                if ir != self.ir {
                    tracing::warn!(
                        serial = self.serial,
                        "the reconnected device reports other IR parameters; keeping the first ones"
                    );
                }
                self.running = Some(running);
                self.missing_depth.restart();
                self.reopened = true;
                self.stats.reconnects += 1;
                self.backoff = self.options.min_backoff;
                tracing::info!(
                    serial = self.serial,
                    reconnects = self.stats.reconnects,
                    "Kinect v2 reconnected"
                );
            }
            Err(err) if !err.is_retryable() => return Err(err),
            Err(err) => {
                self.stats.failed_opens += 1;
                let next = (self.backoff * 2).min(self.options.max_backoff);
                tracing::warn!(serial = self.serial, error = %err, retry_in = ?next, "reconnecting failed");
                self.backoff = next;
            }
        }
        Ok(true)
    }

    /// Converts the frame set in the running device into `frame`:
    /// `Ok(Some(true))` for a frame, `Ok(Some(false))` when the set is
    /// skipped (counted), `Ok(None)` when none came within one wait slice.
    fn convert(&mut self, frame: &mut SourceFrame) -> Result<Option<bool>, Kinect2Error> {
        let Some(running) = self.running.as_mut() else {
            return Ok(None);
        };
        let Some(set) = running.device.wait_for_frames(WAIT_SLICE)? else {
            return Ok(None);
        };
        let arrived_ns = slope_ipc_types::now_ns();
        let arrived = Instant::now();
        running.last_frame = arrived;
        if std::mem::take(&mut self.reopened) {
            // The reopened device's clock starts afresh: continue our time
            // by the wall-clock gap since the last frame before the loss.
            if let Some(before) = self.last_frame_at {
                self.clock.restart(arrived.duration_since(before));
            }
        }
        self.last_frame_at = Some(arrived);
        // Indices count delivered frames only, so a gap downstream always
        // means a cloud was lost there, not a frame the camera spoiled.
        let index = self.next_index;
        let Some((depth, color)) =
            usable_images(&set, self.options.color, &self.serial, &mut self.stats)
        else {
            return Ok(Some(false));
        };
        let registered = register_images(
            &mut running.registration,
            &self.serial,
            &depth,
            color,
            &mut self.undistorted,
            &mut self.registered,
            self.options.registration_filter,
        )?;
        let (width, height) = (self.info.width, self.info.height);
        unmirror_depth(&self.undistorted, width, height, &mut frame.depth);
        match registered {
            Some(format) => {
                let image = frame.color.get_or_insert_with(ColorImage::default);
                unmirror_color(&self.registered, format, width, height, image);
            }
            None => frame.color = None,
        }
        frame.index = index;
        frame.source_stamp_ns = self.clock.stamp(depth.timestamp());
        frame.capture_stamp_ns = arrived_ns;
        drop(set);
        self.next_index = self.next_index.wrapping_add(1);
        self.stats.frames += 1;
        Ok(Some(true))
    }
}

impl Kinect2Source {
    /// Feeds the missing-depth detector after a wait without a frame set;
    /// fails when the depth pipeline has not delivered for its window while
    /// colour flowed or the decoder kept logging errors. Only for the GPU
    /// (and default) pipelines: the CPU decoder cannot fail to initialise,
    /// and depth missing there is a USB problem that reconnecting may cure.
    fn check_depth_flows(&mut self) -> Result<(), Kinect2Error> {
        if self.options.pipeline == Pipeline::Cpu {
            return Ok(());
        }
        let Some(running) = self.running.as_ref() else {
            return Ok(());
        };
        let (color, depth) = running.device.frame_counts();
        let (errors, last_error) = depth_pipeline_errors();
        match self
            .missing_depth
            .observe(Instant::now(), color, depth, errors)
        {
            None => Ok(()),
            Some(missing) => Err(Kinect2Error::DepthPipelineFailed {
                serial: self.serial.clone(),
                pipeline: self.options.pipeline.name(),
                color_frames: missing.color_frames,
                pipeline_errors: missing.pipeline_errors,
                waited_s: missing.waited.as_secs_f64(),
                libfreenect2_log: last_error,
            }),
        }
    }
}

/// Sleeps `duration` in slices of [`WAIT_SLICE`], calling `on_wait` after
/// each; false when `stop` was set first.
fn sleep_watched(
    stop: &StopFlag,
    duration: Duration,
    on_wait: &mut WaitHook,
    stats: &CaptureStats,
) -> bool {
    let deadline = Instant::now() + duration;
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        if !stop.sleep(left.min(WAIT_SLICE)) {
            return false;
        }
        if left <= WAIT_SLICE {
            return true;
        }
        on_wait(stats);
    }
}

/// Starts the device `options` select; with `options.wait_for_device`,
/// retries with backoff (counted in `stats.failed_opens`) until one starts.
/// `Ok(None)` when `stop` was set first.
fn start_waiting(
    context: &Context,
    options: &Kinect2Options,
    stop: &StopFlag,
    on_wait: &mut WaitHook,
    stats: &mut CaptureStats,
) -> Result<Option<Running>, Kinect2Error> {
    let mut backoff = options.min_backoff;
    loop {
        let Some(started) =
            start_interruptible(context, options, &options.device, stop, on_wait, stats)?
        else {
            return Ok(None);
        };
        match started {
            Ok(running) => return Ok(Some(running)),
            Err(err) if options.wait_for_device && err.is_retryable() => {
                stats.failed_opens += 1;
                tracing::warn!(error = %err, retry_in = ?backoff, "waiting for a Kinect v2");
                if !sleep_watched(stop, backoff, on_wait, stats) {
                    return Ok(None);
                }
                backoff = (backoff * 2).min(options.max_backoff);
            }
            Err(err) => return Err(err),
        }
    }
}

/// Opens and starts a device on a thread of its own ([`start_device`]
/// blocks in libfreenect2 for seconds), waiting in slices: `Ok(None)` as
/// soon as `stop` is set, whatever libfreenect2 is doing.
fn start_interruptible(
    context: &Context,
    options: &Kinect2Options,
    selector: &DeviceSelector,
    stop: &StopFlag,
    on_wait: &mut WaitHook,
    stats: &CaptureStats,
) -> Result<Option<Result<Running, Kinect2Error>>, Kinect2Error> {
    let (context, options, selector) = (context.clone(), options.clone(), selector.clone());
    run_interruptible(
        "kinect2-open",
        stop,
        WAIT_SLICE,
        &mut || on_wait(stats),
        move || start_device(&context, &options, &selector),
    )
    .map_err(|err| Kinect2Error::Background(err.to_string()))
}

/// The depth and (when wanted) colour images of `set`, or `None` when the
/// set is skipped: an image missing or flagged by libfreenect2 (counted in
/// `stats` and logged).
fn usable_images<'s>(
    set: &'s FrameSet<'_>,
    want_color: bool,
    serial: &str,
    stats: &mut CaptureStats,
) -> Option<(FrameView<'s>, Option<FrameView<'s>>)> {
    let Some(depth) = set.depth() else {
        stats.malformed += 1;
        tracing::warn!(serial, "frame set without depth; skipped");
        return None;
    };
    let color = if want_color { set.color() } else { None };
    if want_color && color.is_none() {
        stats.malformed += 1;
        tracing::warn!(serial, "frame set without colour; skipped");
        return None;
    }
    let status = depth.status() | color.map_or(0, |c| c.status());
    if status != 0 {
        stats.bad_status += 1;
        tracing::debug!(serial, status, "frame with non-zero status; skipped");
        return None;
    }
    Some((depth, color))
}

/// Checks the images' layouts, then undistorts `depth` into `undistorted`
/// and, with `color`, registers the colour to it into `registered`.
/// Returns the colour's pixel format (`None` without colour). A layout
/// libfreenect2 does not document (e.g. colour still JPEG) will not go away
/// by reconnecting, so it is an error.
fn register_images(
    registration: &mut Registration,
    serial: &str,
    depth: &FrameView<'_>,
    color: Option<FrameView<'_>>,
    undistorted: &mut [f32],
    registered: &mut [u32],
    filter: bool,
) -> Result<Option<FrameFormat>, Kinect2Error> {
    check_layout(serial, depth, DEPTH_WIDTH, DEPTH_HEIGHT, "depth", |f| {
        f == FrameFormat::Float
    })?;
    let Some(color) = color else {
        registration.undistort(depth, undistorted)?;
        return Ok(None);
    };
    check_layout(serial, &color, COLOR_WIDTH, COLOR_HEIGHT, "colour", |f| {
        f == FrameFormat::Bgrx || f == FrameFormat::Rgbx
    })?;
    registration.apply(&color, depth, undistorted, registered, filter)?;
    Ok(Some(color.format()))
}

impl FrameSource for Kinect2Source {
    fn info(&self) -> &SourceInfo {
        &self.info
    }

    fn next_frame(&mut self, frame: &mut SourceFrame) -> Result<bool, SourceError> {
        loop {
            (self.on_wait)(&self.stats);
            if self.stop.is_stopped() {
                return Ok(false);
            }
            if self.running.is_none() {
                if !self.reconnect()? {
                    return Ok(false);
                }
                continue;
            }
            match self.convert(frame) {
                Ok(Some(true)) => {
                    if self.last_report.elapsed() >= REPORT_EVERY {
                        self.last_report = Instant::now();
                        let stats = self.stats;
                        tracing::info!(
                            serial = self.serial,
                            frames = stats.frames,
                            bad_status = stats.bad_status,
                            malformed = stats.malformed,
                            lost = stats.lost,
                            reconnects = stats.reconnects,
                            "Kinect v2 counters"
                        );
                    }
                    return Ok(true);
                }
                Ok(Some(false)) => continue,
                Ok(None) => {
                    self.check_depth_flows()?;
                    let silent = self
                        .running
                        .as_ref()
                        .map_or(Duration::ZERO, |r| r.last_frame.elapsed());
                    if silent >= self.options.frame_timeout {
                        self.stats.lost += 1;
                        tracing::warn!(
                            serial = self.serial,
                            silent = ?silent,
                            lost = self.stats.lost,
                            "no frames from the Kinect v2; reconnecting"
                        );
                        self.close();
                    }
                }
                Err(
                    err @ (Kinect2Error::UnexpectedFrame { .. }
                    | Kinect2Error::BadImageSize { .. }
                    | Kinect2Error::InvalidParams(_)),
                ) => return Err(err.into()),
                Err(err) => {
                    // A failing wait or registration: treat like a lost device.
                    self.stats.lost += 1;
                    tracing::warn!(serial = self.serial, error = %err, "Kinect v2 failed; reconnecting");
                    self.close();
                }
            }
        }
    }
}

impl Drop for Kinect2Source {
    fn drop(&mut self) {
        self.close();
    }
}

/// Opens, configures and starts a device, and builds its registration from
/// the parameters it reports once started.
fn start_device(
    context: &Context,
    options: &Kinect2Options,
    selector: &DeviceSelector,
) -> Result<Running, Kinect2Error> {
    let mut device = context.open(selector, options.pipeline, options.gpu_device)?;
    device.set_depth_config(&options.depth)?;
    let streams = if options.color {
        Streams::DEPTH_AND_COLOR
    } else {
        Streams::DEPTH
    };
    device.start(streams)?;
    match device.firmware_version() {
        Ok(firmware) => tracing::debug!(serial = device.serial(), firmware, "device started"),
        Err(err) => tracing::debug!(error = %err, "could not read the firmware version"),
    }
    // libfreenect2 reads the factory calibration during start.
    let ir = device.ir_params()?;
    let color = device.color_params()?;
    let registration = Registration::new(&ir, &color)?;
    Ok(Running {
        device,
        registration,
        last_frame: Instant::now(),
    })
}

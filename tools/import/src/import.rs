//! The import itself: one pass over the bag's messages ([`Importer`]).
//!
//! Depth images are held back (at most [`MAX_PENDING`]) until the camera
//! info has come, since recording.toml, written first, needs the
//! intrinsics; and, when the bag has `/tf_static`, until the transform to
//! the camera is known or [`MAX_WAIT_FOR_TF`] images have passed without
//! it (the mount is recording.toml's too).

use std::ops::ControlFlow;
use std::path::Path;

use anyhow::{bail, Context};
use indicatif::ProgressBar;
use slope_sensor::publish::StopFlag;
use slope_sensor::recording::{
    ColorImage, DepthImage, DepthInfo, MountInfo, RecordingMeta, RecordingWriter, TruthInfo,
};
use slope_tools::ros2_messages::{CameraInfo, CompressedImage, Header, Image, TfMessage};

use crate::args::ImportArgs;
use crate::bag::{BagMessage, Serialization, Truncated};
use crate::color::{image_to_color, WaitingColors, MAX_DEPTH_WAIT};
use crate::depth::{compressed_to_depth, image_to_depth, UNIT_M};
use crate::messages::Decode;
use crate::mount::StaticTransforms;
use crate::topics::{Chosen, DepthKind};

/// Depth images held back waiting for the camera info: more, and the
/// camera info is taken to be missing.
pub const MAX_PENDING: usize = 300;
/// Depth images held back waiting for `/tf_static`'s camera transform.
pub const MAX_WAIT_FOR_TF: usize = 30;

/// What an import did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ImportStats {
    /// Frames written into the recording.
    pub written: u64,
    /// Depth images read from the bag (before --start/--duration/--every).
    pub depth_messages: u64,
    /// Frames written with a colour image.
    pub with_color: u64,
    /// Depth images skipped: unreadable, or stamped before the one before.
    pub skipped: u64,
    /// Set when a signal stopped the import.
    pub interrupted: bool,
}

/// The state of one import.
pub struct Importer<'a> {
    args: &'a ImportArgs,
    chosen: &'a Chosen,
    serialization: Serialization,
    out: &'a Path,
    progress: ProgressBar,
    info: Option<DepthInfo>,
    transforms: StaticTransforms,
    camera_frame: Option<String>,
    /// Depth images held back (stamp, depth, its colour once found).
    pending: Vec<(u64, DepthImage, Option<ColorImage>)>,
    colors: WaitingColors,
    /// Set once the colour topic turned out unusable (warned once).
    color_failed: bool,
    writer: Option<RecordingWriter>,
    first_stamp_ns: Option<u64>,
    last_stamp_ns: Option<u64>,
    in_window: u64,
    /// The error that ended the pass.
    failure: Option<anyhow::Error>,
    pub stats: ImportStats,
}

/// `stamp` in ns; `None` for one before the epoch or unset (0).
fn stamp_ns(header: &Header) -> Option<u64> {
    header.stamp.to_ns().filter(|&ns| ns > 0)
}

impl<'a> Importer<'a> {
    pub fn new(
        args: &'a ImportArgs,
        chosen: &'a Chosen,
        serialization: Serialization,
        out: &'a Path,
        progress: ProgressBar,
    ) -> Self {
        Self {
            args,
            chosen,
            serialization,
            out,
            progress,
            info: None,
            transforms: StaticTransforms::default(),
            camera_frame: None,
            pending: Vec::new(),
            colors: WaitingColors::default(),
            color_failed: false,
            writer: None,
            first_stamp_ns: None,
            last_stamp_ns: None,
            in_window: 0,
            failure: None,
            stats: ImportStats::default(),
        }
    }

    /// Handles one message; breaks when done, stopped or failed.
    pub fn on_message(&mut self, message: BagMessage<'_>, stop: &StopFlag) -> ControlFlow<()> {
        if stop.is_stopped() {
            self.stats.interrupted = true;
            return ControlFlow::Break(());
        }
        let result = if Some(message.topic) == self.chosen.tf_static.as_deref() {
            self.on_tf_static(message.data);
            Ok(ControlFlow::Continue(()))
        } else if message.topic == self.chosen.info {
            self.on_camera_info(message.data)
                .map(|()| ControlFlow::Continue(()))
        } else if Some(message.topic) == self.chosen.color.as_deref() {
            self.on_color(message.data);
            Ok(ControlFlow::Continue(()))
        } else if message.topic == self.chosen.depth {
            self.progress.inc(1);
            self.on_depth(message)
        } else {
            Ok(ControlFlow::Continue(()))
        };
        match result.and_then(|flow| self.flush().map(|()| flow)) {
            Ok(flow) => flow,
            Err(err) => {
                self.failure = Some(err);
                ControlFlow::Break(())
            }
        }
    }

    fn on_tf_static(&mut self, data: &[u8]) {
        match TfMessage::decode(data, self.serialization) {
            Ok(message) => self.transforms.add(&message),
            Err(err) => tracing::warn!(
                "{}: {err}; ignored",
                self.chosen.tf_static.as_deref().unwrap_or("")
            ),
        }
    }

    /// A colour image: given to the depth image of its stamp, or kept for
    /// it. One that cannot be used ends the colour stream (a warning).
    fn on_color(&mut self, data: &[u8]) {
        if self.color_failed {
            return;
        }
        let topic = self.chosen.color.as_deref().unwrap_or("");
        let decoded = Image::decode(data, self.serialization)
            .map_err(|e| e.to_string())
            .and_then(|image| {
                let stamp = stamp_ns(&image.header);
                image_to_color(&image).map(|color| (stamp, color))
            });
        let (stamp, color) = match decoded {
            Ok((Some(stamp), color)) => (stamp, color),
            Ok((None, _)) => {
                return self.give_up_color(topic, "its images have no stamp to match".to_string())
            }
            Err(why) => return self.give_up_color(topic, why),
        };
        if let Some(info) = self.info {
            if (color.width, color.height) != (info.width, info.height) {
                let why = format!(
                    "its images are {} x {}, the depth images {} x {}: not registered to them",
                    color.width, color.height, info.width, info.height
                );
                return self.give_up_color(topic, why);
            }
        }
        match self
            .pending
            .iter_mut()
            .find(|(s, _, c)| *s == stamp && c.is_none())
        {
            Some((_, _, slot)) => *slot = Some(color),
            None => self.colors.push(stamp, color),
        }
    }

    fn give_up_color(&mut self, topic: &str, why: String) {
        tracing::warn!("{topic}: {why}; importing without colour (--no-color to say so)");
        self.color_failed = true;
    }

    /// The first camera info gives the intrinsics.
    fn on_camera_info(&mut self, data: &[u8]) -> anyhow::Result<()> {
        if self.info.is_some() {
            return Ok(());
        }
        let topic = &self.chosen.info;
        let info = CameraInfo::decode(data, self.serialization)
            .with_context(|| format!("cannot read {topic}"))?;
        let k = info.k;
        let (fx, fy, cx, cy) = (k[0], k[4], k[2], k[5]);
        if !(fx > 0.0
            && fy > 0.0
            && fx.is_finite()
            && fy.is_finite()
            && cx.is_finite()
            && cy.is_finite())
        {
            bail!("{topic}: its K gives no pinhole camera (fx {fx}, fy {fy}, cx {cx}, cy {cy})");
        }
        if info.width == 0 || info.height == 0 {
            bail!(
                "{topic}: the camera info says the image is {} x {}",
                info.width,
                info.height
            );
        }
        if info.d.iter().any(|&d| d != 0.0) {
            tracing::warn!(
                "{topic} has distortion coefficients {:?}: the depth images are taken as undistorted \
                 (use the rectified topic, image_depth_rect)",
                info.d
            );
        }
        self.info = Some(DepthInfo {
            width: info.width,
            height: info.height,
            unit_m: UNIT_M,
            fx,
            fy,
            cx,
            cy,
        });
        Ok(())
    }

    /// Decodes a depth image, or says why not.
    fn decode_depth(&self, data: &[u8]) -> anyhow::Result<(Header, DepthImage)> {
        let mut depth = DepthImage::default();
        let header = match self.chosen.kind {
            DepthKind::Raw => {
                let image = Image::decode(data, self.serialization)?;
                image_to_depth(&image, &mut depth)?;
                image.header
            }
            DepthKind::Compressed => {
                let image = CompressedImage::decode(data, self.serialization)?;
                compressed_to_depth(&image, &mut depth)?;
                image.header
            }
        };
        Ok((header, depth))
    }

    fn on_depth(&mut self, message: BagMessage<'_>) -> anyhow::Result<ControlFlow<()>> {
        self.stats.depth_messages += 1;
        let index = self.stats.depth_messages;
        let (header, depth) = match self.decode_depth(message.data) {
            Ok(decoded) => decoded,
            // Before the first frame, an image that cannot be imported is
            // what the topic holds: an error. Later, one bad message.
            Err(err) if self.stats.written == 0 && self.pending.is_empty() => {
                return Err(err.context(format!(
                    "cannot import {} (depth image {index})",
                    self.chosen.depth
                )));
            }
            Err(err) => {
                tracing::warn!(
                    "{}: skipping depth image {index}: {err:#}",
                    self.chosen.depth
                );
                self.stats.skipped += 1;
                return Ok(ControlFlow::Continue(()));
            }
        };
        let stamp = stamp_ns(&header).unwrap_or(message.log_time_ns);
        let first = *self.first_stamp_ns.get_or_insert(stamp);
        let since_s = stamp.saturating_sub(first) as f64 * 1e-9;
        let start = self.args.start.unwrap_or(0.0);
        if since_s < start {
            return Ok(ControlFlow::Continue(()));
        }
        if self.args.duration.is_some_and(|d| since_s > start + d) {
            return Ok(ControlFlow::Break(()));
        }
        self.in_window += 1;
        if !(self.in_window - 1).is_multiple_of(self.args.every) {
            return Ok(ControlFlow::Continue(()));
        }
        if self.last_stamp_ns.is_some_and(|last| stamp < last) {
            tracing::warn!(
                "{}: depth image {index} is stamped before the one before; skipped",
                self.chosen.depth
            );
            self.stats.skipped += 1;
            return Ok(ControlFlow::Continue(()));
        }
        self.last_stamp_ns = Some(stamp);
        self.camera_frame
            .get_or_insert_with(|| header.frame_id.clone());
        let color = self.colors.take(stamp);
        self.pending.push((stamp, depth, color));
        Ok(ControlFlow::Continue(()))
    }

    /// Whether the mount can be decided: all of it from flags, the
    /// transform known, no `/tf_static` in the bag, or waited long enough.
    fn mount_ready(&self) -> bool {
        let flags = &self.args.mount;
        let all_flags =
            flags.height_m.is_some() && flags.pitch_deg.is_some() && flags.roll_deg.is_some();
        all_flags
            || self.chosen.tf_static.is_none()
            || self.pending.len() >= MAX_WAIT_FOR_TF
            || self.tf_mount().is_some()
    }

    fn tf_mount(&self) -> Option<MountInfo> {
        let camera = self.camera_frame.as_deref()?;
        self.transforms.mount(&self.args.base_frame, camera)
    }

    /// The mount: `/tf_static`'s, the flags over it key by key.
    fn mount(&self) -> anyhow::Result<MountInfo> {
        let tf = self.tf_mount();
        match (&tf, self.camera_frame.as_deref()) {
            (Some(m), camera) => tracing::info!(
                base = self.args.base_frame,
                camera,
                height_m = m.height_m,
                pitch_deg = m.pitch_deg,
                roll_deg = m.roll_deg,
                "mount from /tf_static"
            ),
            (None, camera) if self.chosen.tf_static.is_some() => tracing::warn!(
                "no transform from {} to the camera's frame {:?} in /tf_static (its frames: {}); \
                 the mount is what --mount-* say (--base-frame chooses the base)",
                self.args.base_frame,
                camera.unwrap_or(""),
                self.transforms.frames().join(", ")
            ),
            (None, _) => {}
        }
        let tf = tf.unwrap_or_default();
        let flags = &self.args.mount;
        let mount = MountInfo {
            height_m: flags.height_m.or(tf.height_m),
            pitch_deg: flags.pitch_deg.or(tf.pitch_deg),
            roll_deg: flags.roll_deg.or(tf.roll_deg),
        };
        if let Err((key, value, reason)) = mount.check() {
            bail!(
                "the mount from /tf_static ({} to the camera) has {key} {value}: {reason}; give \
                 it with --mount-* (or another --base-frame)",
                self.args.base_frame
            );
        }
        Ok(mount)
    }

    /// Creates the recording once it can be, and writes the frames held
    /// back.
    fn flush(&mut self) -> anyhow::Result<()> {
        if self.writer.is_none() {
            let Some(info) = self.info else {
                if self.pending.len() > MAX_PENDING {
                    bail!(
                        "no camera info on {} within the first {MAX_PENDING} depth images of {}; \
                         choose the camera info topic with --info-topic",
                        self.chosen.info,
                        self.chosen.depth
                    );
                }
                return Ok(());
            };
            if self.pending.is_empty() || !self.mount_ready() {
                return Ok(());
            }
            self.create(info)?;
        }
        self.write_pending(false)
    }

    fn create(&mut self, info: DepthInfo) -> anyhow::Result<()> {
        if let Some((_, depth, _)) = self.pending.first() {
            if (depth.width, depth.height) != (info.width, info.height) {
                bail!(
                    "the depth images of {} are {} x {}, but {} says {} x {}: choose the camera \
                     info of the depth camera with --info-topic",
                    self.chosen.depth,
                    depth.width,
                    depth.height,
                    self.chosen.info,
                    info.width,
                    info.height
                );
            }
        }
        let meta = RecordingMeta {
            sensor: self.args.sensor.clone(),
            depth: info,
            mount: self.mount()?,
            truth: TruthInfo::default(),
        };
        let writer = RecordingWriter::create(self.out, &meta, false)
            .with_context(|| format!("cannot create the recording {}", self.out.display()))?;
        self.writer = Some(writer);
        Ok(())
    }

    /// Writes the frames held back, oldest first; one still waiting for
    /// its colour image stays (unless `all`, or [`MAX_DEPTH_WAIT`] newer
    /// depth images wait behind it).
    fn write_pending(&mut self, all: bool) -> anyhow::Result<()> {
        let Some(writer) = self.writer.as_mut() else {
            return Ok(());
        };
        let colour = self.chosen.color.is_some() && !self.color_failed;
        while let Some((_, _, color)) = self.pending.first() {
            if colour && color.is_none() && !all && self.pending.len() <= MAX_DEPTH_WAIT {
                break;
            }
            let (stamp, depth, color) = self.pending.remove(0);
            self.stats.with_color += u64::from(color.is_some());
            writer
                .write_frame(stamp, &depth, color.as_ref(), None)
                .with_context(|| {
                    format!(
                        "cannot write frame {} of {} (its image is {} x {}; the camera info says \
                         otherwise?)",
                        writer.frames_written(),
                        self.out.display(),
                        depth.width,
                        depth.height
                    )
                })?;
            self.stats.written += 1;
        }
        Ok(())
    }

    /// Writes what is held back, finishes the recording and says how the
    /// pass ended: an error when it failed, found nothing, or the bag was
    /// cut short (the recording keeps what was read).
    pub fn finish(mut self, truncated: Option<Truncated>) -> anyhow::Result<ImportStats> {
        self.progress.finish_and_clear();
        if let Some(err) = self.failure.take() {
            self.abandon();
            return Err(err);
        }
        if self.writer.is_none() && !self.pending.is_empty() {
            if let Some(info) = self.info {
                self.create(info)?;
            }
        }
        self.write_pending(true)?;
        let Some(writer) = self.writer.take() else {
            return Err(self.nothing_read(truncated));
        };
        writer
            .finish()
            .with_context(|| format!("cannot finish the recording {}", self.out.display()))?;
        if let Some(t) = truncated {
            let at = t.last_log_time_ns.map_or_else(String::new, |ns| {
                format!(", the last logged at {:.3} s", ns as f64 * 1e-9)
            });
            bail!(
                "{} stops early, after {} messages{at}: {}; {} holds the {} frames read before",
                self.args.bag.display(),
                t.messages,
                t.error,
                self.out.display(),
                self.stats.written
            );
        }
        Ok(self.stats)
    }

    /// The error of a pass that wrote nothing.
    fn nothing_read(&self, truncated: Option<Truncated>) -> anyhow::Error {
        let bag = self.args.bag.display();
        let why = if self.stats.depth_messages == 0 {
            format!("{bag} has no message on {}", self.chosen.depth)
        } else if self.info.is_none() {
            format!(
                "the camera info never arrived on {} ({} depth images read); the intrinsics come \
                 from it",
                self.chosen.info, self.stats.depth_messages
            )
        } else {
            format!(
                "none of the {} depth images of {} is within --start/--duration",
                self.stats.depth_messages, self.chosen.depth
            )
        };
        match truncated {
            Some(t) => anyhow::anyhow!(
                "{why}; {bag} stops early after {} messages: {}",
                t.messages,
                t.error
            ),
            None => anyhow::anyhow!("{why}; nothing was written"),
        }
    }

    /// After a failure: a recording with frames is finished (it stays
    /// valid); none is left empty.
    fn abandon(&mut self) {
        if let Some(writer) = self.writer.take() {
            if let Err(err) = writer.finish() {
                tracing::warn!("cannot finish {}: {err}", self.out.display());
            }
        }
    }
}

//! One recording under every method ([`evaluate_recording`]): each frame
//! read, projected and estimated in order, the pictures and clouds asked
//! for written, the results gathered into one report per method.

use indicatif::ProgressBar;
use slope_ipc_types::{CloudPoint, EstimateStatus};
use slope_pipeline::{CloudView, Estimator, FrameInfo};
use slope_sensor::error_chain::ErrorChain;
use slope_sensor::frame_reads::{read_frame_images, Colour};
use slope_sensor::publish::StopFlag;
use slope_sensor::recording::{DepthImage, FrameEntry, Recording};

use super::frame::{frame_result, FrameDetails, FrameResult};
use super::summary::MethodReport;
use crate::eval_artifacts::{Artifacts, Snapshot};

/// Where one recording's pictures and clouds go.
pub(super) struct ArtifactTarget<'a> {
    pub(super) artifacts: &'a Artifacts,
    /// File-name stem of the recording.
    pub(super) name: &'a str,
}

/// Runs every estimator on every frame of one recording, in order, until
/// `stop` is set, writing the pictures and clouds asked for; returns the
/// reports, what could not be written and how many frames were evaluated.
pub(super) fn evaluate_recording(
    recording: &Recording,
    label: &str,
    frames: &[FrameEntry],
    estimators: &mut [Estimator],
    target: &ArtifactTarget<'_>,
    bar: &ProgressBar,
    stop: &StopFlag,
) -> (Vec<MethodReport>, Vec<String>, usize) {
    let projector = recording.projector();
    let mut depth = DepthImage::default();
    let mut points = vec![CloudPoint::INVALID; projector.len()];
    let mut tally = Tally {
        label,
        target,
        bar,
        results: vec![Vec::with_capacity(frames.len()); estimators.len()],
        failures: Vec::new(),
        bad: 0,
        first_bad: None,
    };
    let meta = recording.meta();
    let (width, height) = (meta.depth.width as usize, meta.depth.height as usize);
    let mut evaluated = 0;
    for (position, frame) in frames.iter().enumerate() {
        if stop.is_stopped() {
            break;
        }
        let wanted = target.artifacts.wants(position, frame.index, frames.len());
        let truth_deg = recording.truth_deg(frame);
        // On a thread of its own: a stop request ends a read that blocks.
        let read = read_frame_images(recording, frame, &mut depth, Colour::Skip, Some(stop));
        let read = match read {
            Ok(Some(images)) => images.depth.map_err(|err| ErrorChain(&err).to_string()),
            Ok(None) => break,
            Err(err) => Err(err.to_string()),
        };
        evaluated += 1;
        match read {
            Err(error) => {
                tally.bad_frame(frame.index, truth_deg, wanted, error);
            }
            Ok(()) => {
                projector.project_into(&depth.data, None, &mut points);
                let view = CloudView {
                    points: &points,
                    width,
                    height,
                    intrinsics: recording.intrinsics(),
                    mount: recording.mount(),
                };
                let info = FrameInfo {
                    index: frame.index,
                    stamp_ns: frame.timestamp_ns,
                };
                let size = (meta.depth.width, meta.depth.height);
                tally.estimate(estimators, &view, info, truth_deg, wanted.then_some(size));
            }
        }
    }
    tally.finish(estimators, evaluated)
}

/// What one recording's frames gave so far, per method, and what went
/// wrong.
struct Tally<'a> {
    label: &'a str,
    target: &'a ArtifactTarget<'a>,
    bar: &'a ProgressBar,
    /// One list per estimator, in the estimators' order.
    results: Vec<Vec<FrameResult>>,
    /// What could not be rendered or evaluated.
    failures: Vec<String>,
    /// Frames whose depth image could not be read.
    bad: usize,
    /// The first such frame's error.
    first_bad: Option<String>,
}

impl Tally<'_> {
    /// A frame whose depth image could not be read: `bad_frame` under every
    /// method, and a failure if it was the frame to render.
    fn bad_frame(&mut self, index: u64, truth_deg: Option<f64>, wanted: bool, error: String) {
        let (label, bar) = (self.label, self.bar);
        bar.suspend(|| tracing::warn!(recording = label, frame = index, "bad frame: {error}"));
        if wanted && self.target.artifacts.frame == Some(index) {
            self.failures.push(format!(
                "cannot render frame {index} of {label}: it is a bad frame: {error}"
            ));
        } else if wanted {
            bar.suspend(|| {
                tracing::warn!(recording = label, frame = index, "not rendered: bad frame")
            });
        }
        for per_method in &mut self.results {
            per_method.push(FrameResult {
                index,
                status: EstimateStatus::BadFrame.name(),
                slope_deg: None,
                std_deg: None,
                distance_m: None,
                truth_deg,
                ms: None,
                error: Some(error.clone()),
                details: FrameDetails::default(),
            });
        }
        bar.inc(self.results.len() as u64);
        self.bad += 1;
        self.first_bad.get_or_insert(error);
    }

    /// Runs every estimator on a frame's cloud; `render` is the depth
    /// image's width and height when the frame's pictures and clouds are
    /// wanted.
    fn estimate(
        &mut self,
        estimators: &mut [Estimator],
        view: &CloudView<'_>,
        info: FrameInfo,
        truth_deg: Option<f64>,
        render: Option<(u32, u32)>,
    ) {
        let label = self.label;
        for (estimator, per_method) in estimators.iter_mut().zip(&mut self.results) {
            let estimate = estimator.estimate_frame(view, info);
            tracing::debug!(
                recording = label,
                frame = info.index,
                method = estimate.method.name(),
                status = estimate.status.name(),
                slope_deg = estimate.slope_deg,
                ms = estimate.timings.total_ms,
                "estimated"
            );
            per_method.push(frame_result(info.index, truth_deg, &estimate));
            if let Some((width, height)) = render {
                let snapshot = Snapshot {
                    recording: label,
                    name: self.target.name,
                    index: info.index,
                    points: view.points,
                    width,
                    height,
                    intrinsics: view.intrinsics,
                    estimate: &estimate,
                    inspection: estimator.inspection(),
                    truth_deg,
                };
                write(
                    self.target.artifacts,
                    self.bar,
                    &snapshot,
                    &mut self.failures,
                );
            }
            self.bar.inc(1);
        }
    }

    /// The reports, one per estimator, and the failures, with one more when
    /// none of the `evaluated` frames could be read.
    fn finish(
        mut self,
        estimators: &[Estimator],
        evaluated: usize,
    ) -> (Vec<MethodReport>, Vec<String>, usize) {
        let (label, bad) = (self.label, self.bad);
        if evaluated > 0 && bad == evaluated {
            // Some bad frames are counted in the report; none readable at all
            // is a broken recording.
            self.failures.push(format!(
                "cannot evaluate {label}: none of its {bad} frame(s) could be read (the first: {})",
                self.first_bad.unwrap_or_default()
            ));
        }
        let reports = estimators
            .iter()
            .zip(self.results)
            .map(|(estimator, estimates)| {
                MethodReport::new(label.to_string(), estimator.config().method, estimates)
            })
            .collect();
        (reports, self.failures, evaluated)
    }
}

/// Writes a frame's pictures and clouds; what cannot be written goes to
/// `failures`.
fn write(
    artifacts: &Artifacts,
    bar: &ProgressBar,
    snapshot: &Snapshot<'_>,
    failures: &mut Vec<String>,
) {
    match bar.suspend(|| artifacts.write(snapshot)) {
        Ok(paths) => {
            for path in paths {
                bar.suspend(|| tracing::info!(path = %path.display(), "written"));
            }
        }
        Err(err) => failures.push(format!("{err:#}")),
    }
}

//! Writing off the receiving thread: the [`Sink`] of a topic recording
//! lives on a thread of its own, fed through a bounded queue, so that
//! encoding (PNG, zstd, base64) never keeps the receiving thread from the
//! subscriber's buffer. The receiving thread only copies a cloud's images
//! (and, for MCAP, its points) out of shared memory.
//!
//! The queue holds [`QUEUE_FRAMES`] frames; when the writer falls further
//! behind, the receiving thread waits for it (and clouds the subscriber
//! cannot hold meanwhile are counted as missed). When a write fails, the
//! thread ends with the error and hands the sink back.

use std::path::PathBuf;
use std::thread::JoinHandle;

use anyhow::Context;
use crossbeam_channel::{bounded, Sender};
use slope_ipc_types::{CloudHeader, CloudPoint, SlopeEstimate, Surfaces};
use slope_sensor::recording::{ColorImage, DepthImage};

use super::sink::Sink;

/// Frames the queue holds: 2 s at 30 Hz (about 240 MB of MCAP frames).
pub(super) const QUEUE_FRAMES: usize = 60;

/// One frame to write, copied out of its cloud sample.
pub(super) struct QueuedFrame {
    pub header: CloudHeader,
    /// The cloud's points (MCAP only; empty for a recording directory).
    pub points: Vec<CloudPoint>,
    pub depth: DepthImage,
    pub color: Option<ColorImage>,
}

enum Job {
    Frame(Box<QueuedFrame>),
    Estimate(Box<SlopeEstimate>),
    Surfaces(Box<Surfaces>),
}

/// What the writer thread did: the sink, the frames it wrote and its error.
pub(super) struct Written {
    pub sink: Sink,
    pub frames: u64,
    pub result: anyhow::Result<()>,
}

/// The writer thread of a sink.
pub(super) struct SinkThread {
    jobs: Sender<Job>,
    handle: JoinHandle<Written>,
}

impl SinkThread {
    /// Starts the thread that writes into `sink` (`out`: for messages).
    pub(super) fn spawn(sink: Sink, out: PathBuf) -> anyhow::Result<Self> {
        let (jobs, queue) = bounded::<Job>(QUEUE_FRAMES);
        let handle = std::thread::Builder::new()
            .name("record-writer".into())
            .spawn(move || {
                let mut sink = sink;
                let mut frames = 0;
                for job in queue {
                    let result = match job {
                        Job::Frame(frame) => sink
                            .write(
                                &frame.header,
                                &frame.points,
                                &frame.depth,
                                frame.color.as_ref(),
                                frames,
                                &out,
                            )
                            .map(|()| frames += 1),
                        Job::Estimate(estimate) => match &mut sink {
                            Sink::Mcap(mcap) => mcap.write_estimate(&estimate),
                            Sink::Recording(..) => Ok(()),
                        },
                        Job::Surfaces(surfaces) => match &mut sink {
                            Sink::Mcap(mcap) => mcap.write_surfaces(&surfaces),
                            Sink::Recording(..) => Ok(()),
                        },
                    };
                    if let Err(err) = result {
                        return Written {
                            sink,
                            frames,
                            result: Err(err),
                        };
                    }
                }
                Written {
                    sink,
                    frames,
                    result: Ok(()),
                }
            })
            .context("cannot start the recorder's writer thread")?;
        Ok(Self { jobs, handle })
    }

    /// Queues `frame`, waiting while the queue is full. False when the
    /// writer has stopped (its error comes with [`Self::join`]).
    pub(super) fn write(&self, frame: QueuedFrame) -> bool {
        self.jobs.send(Job::Frame(Box::new(frame))).is_ok()
    }

    /// Queues an estimate (MCAP; ignored for a recording directory).
    pub(super) fn write_estimate(&self, estimate: SlopeEstimate) -> bool {
        self.jobs.send(Job::Estimate(Box::new(estimate))).is_ok()
    }

    /// Queues a frame's surfaces (MCAP; ignored for a recording directory).
    pub(super) fn write_surfaces(&self, surfaces: Surfaces) -> bool {
        self.jobs.send(Job::Surfaces(Box::new(surfaces))).is_ok()
    }

    /// Waits until everything queued is written (or the writer failed).
    pub(super) fn join(self) -> anyhow::Result<Written> {
        drop(self.jobs);
        self.handle
            .join()
            .map_err(|_| anyhow::anyhow!("the recorder's writer thread panicked"))
    }
}

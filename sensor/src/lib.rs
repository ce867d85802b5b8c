//! The sensor side of slope: recordings on disk, depth-to-cloud projection,
//! frame sources (recordings, the Kinect v2) and the zero-copy publishing
//! path into iceoryx2 shared memory.

pub mod cloud_checks;
pub mod device_lock;
pub mod error_chain;
pub mod frame_reads;
pub mod input_file;
pub mod interruptible;
pub mod ipc;
pub mod kinect2;
pub mod missing_depth;
pub mod projection;
pub mod publish;
pub mod recording;
pub mod source;

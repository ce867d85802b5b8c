//! Which device and which depth pipeline: the names on command lines and
//! in config files, the selector, the serials open in a context, and the
//! check that libfreenect2 opened the device asked for. Pure: whether a
//! pipeline is built into the installed libfreenect2 is the device layer's
//! question (`Pipeline::is_available`, feature `kinect2`).

// Without the `kinect2` feature the checks the device layer makes are
// called by the tests only.
#![cfg_attr(not(feature = "kinect2"), allow(dead_code))]

use std::collections::HashSet;
use std::fmt;
use std::str::FromStr;

use super::error::Kinect2Error;

/// A depth packet pipeline: where libfreenect2 decodes depth.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Pipeline {
    /// libfreenect2's own choice (the best one built in; GL first).
    #[default]
    Default,
    Cpu,
    OpenCl,
    OpenClKde,
    Cuda,
    CudaKde,
    /// Needs a display (an OpenGL context); headless robots want cl/cuda/cpu.
    OpenGl,
}

impl Pipeline {
    pub const ALL: [Pipeline; 7] = [
        Self::Default,
        Self::Cpu,
        Self::OpenCl,
        Self::OpenClKde,
        Self::Cuda,
        Self::CudaKde,
        Self::OpenGl,
    ];

    /// The name used on command lines and in config files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Default => "default",
            Self::Cpu => "cpu",
            Self::OpenCl => "cl",
            Self::OpenClKde => "clkde",
            Self::Cuda => "cuda",
            Self::CudaKde => "cudakde",
            Self::OpenGl => "gl",
        }
    }
}

impl fmt::Display for Pipeline {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// An unknown pipeline name.
#[derive(Debug, Clone, thiserror::Error)]
#[error("unknown depth pipeline '{0}' (one of: default, cpu, cl, clkde, cuda, cudakde, gl)")]
pub struct UnknownPipeline(pub String);

impl FromStr for Pipeline {
    type Err = UnknownPipeline;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|p| p.name().eq_ignore_ascii_case(text.trim()))
            .ok_or_else(|| UnknownPipeline(text.to_string()))
    }
}

/// Which device to open.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum DeviceSelector {
    /// The first one enumerated.
    #[default]
    First,
    /// By enumeration index (not stable across re-plugging).
    Index(u32),
    /// By serial number (stable; what a robot should use).
    Serial(String),
}

/// The serials of the open devices of one context.
#[derive(Debug, Default)]
pub(crate) struct OpenSerials(HashSet<String>);

impl OpenSerials {
    /// Marks `serial` open; [`Kinect2Error::AlreadyOpen`] if it already is.
    pub(crate) fn claim(&mut self, serial: &str) -> Result<(), Kinect2Error> {
        if self.0.insert(serial.to_string()) {
            Ok(())
        } else {
            Err(Kinect2Error::AlreadyOpen {
                serial: serial.to_string(),
            })
        }
    }

    /// Marks `serial` closed.
    pub(crate) fn release(&mut self, serial: &str) {
        self.0.remove(serial);
    }

    pub(crate) fn is_open(&self, serial: &str) -> bool {
        self.0.contains(serial)
    }
}

/// The kind of device in lock file names (`slope-kinect2-<serial>.lock`).
pub const LOCK_KIND: &str = "kinect2";

/// `Ok` when libfreenect2 opened the device that was asked for.
pub fn check_opened_serial(requested: &str, opened: &str) -> Result<(), Kinect2Error> {
    if requested == opened {
        Ok(())
    } else {
        Err(Kinect2Error::SerialMismatch {
            requested: requested.to_string(),
            opened: opened.to_string(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_serial_can_be_open_only_once_at_a_time() {
        let mut open = OpenSerials::default();
        open.claim("111").expect("first open");
        open.claim("222").expect("another device");
        match open.claim("111") {
            Err(Kinect2Error::AlreadyOpen { serial }) => assert_eq!(serial, "111"),
            other => panic!("expected AlreadyOpen, got {other:?}"),
        }
        assert!(open.is_open("111") && open.is_open("222"));
        open.release("111");
        assert!(!open.is_open("111"));
        open.claim("111").expect("open again after closing");
        let message = Kinect2Error::AlreadyOpen {
            serial: "111".into(),
        }
        .to_string();
        assert!(message.contains("111") && message.contains("already open"));
    }

    #[test]
    fn a_device_other_than_the_requested_one_is_an_error() {
        check_opened_serial("011054343347", "011054343347").expect("the same device");
        match check_opened_serial("011054343347", "003623251547") {
            Err(err @ Kinect2Error::SerialMismatch { .. }) => {
                let message = err.to_string();
                assert!(
                    message.contains("011054343347") && message.contains("003623251547"),
                    "{message}"
                );
            }
            other => panic!("expected SerialMismatch, got {other:?}"),
        }
    }

    /// Every pipeline is found by its name (in any case, with spaces
    /// around), and an unknown name is refused naming the known ones.
    #[test]
    fn pipelines_are_found_by_name() {
        for pipeline in Pipeline::ALL {
            assert_eq!(pipeline.name().parse::<Pipeline>().ok(), Some(pipeline));
            assert_eq!(pipeline.to_string(), pipeline.name());
        }
        assert_eq!(" CL ".parse::<Pipeline>().ok(), Some(Pipeline::OpenCl));
        let err = "vulkan".parse::<Pipeline>().expect_err("unknown");
        let message = err.to_string();
        assert!(message.contains("'vulkan'"), "{message}");
        for pipeline in Pipeline::ALL {
            assert!(message.contains(pipeline.name()), "{message}");
        }
    }
}

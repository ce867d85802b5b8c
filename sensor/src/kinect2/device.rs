//! Safe handles over the shim: the libfreenect2 context, an opened device,
//! its frame listener and the frame sets it hands out.
//!
//! Ownership mirrors what libfreenect2 needs:
//! - a [`Device`] keeps its [`Context`] alive (libfreenect2 deletes the
//!   devices of a context when the context goes);
//! - a device owns its listeners and frees them only after the device itself
//!   is gone, because libfreenect2's processing threads may still deliver a
//!   frame until the device's destructor has joined them;
//! - a [`FrameSet`] borrows the device mutably, so nothing can stop the
//!   streams or wait again while its frames are in use, and gives the frames
//!   back to libfreenect2 when dropped.

use std::ffi::c_char;
use std::fmt;
use std::marker::PhantomData;
use std::ptr::NonNull;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use super::choice::{check_opened_serial, DeviceSelector, OpenSerials, Pipeline, LOCK_KIND};
use super::error::{Kinect2Error, ShimStatus};
use super::ffi_error::{check, non_null};
use super::frame::{FrameFormat, FrameMetadata, FrameView};
use super::log;
use super::params::{ColorParams, DepthConfig, IrParams};
use super::sys;
use crate::device_lock::DeviceLock;

// The codes `frame.rs` and `log.rs` mirror are the shim's.
const _: () = {
    assert!(FrameFormat::INVALID_CODE == sys::f2s_frame_format::F2S_FORMAT_INVALID.0);
    assert!(FrameFormat::RAW_CODE == sys::f2s_frame_format::F2S_FORMAT_RAW.0);
    assert!(FrameFormat::FLOAT_CODE == sys::f2s_frame_format::F2S_FORMAT_FLOAT.0);
    assert!(FrameFormat::BGRX_CODE == sys::f2s_frame_format::F2S_FORMAT_BGRX.0);
    assert!(FrameFormat::RGBX_CODE == sys::f2s_frame_format::F2S_FORMAT_RGBX.0);
    assert!(FrameFormat::GRAY_CODE == sys::f2s_frame_format::F2S_FORMAT_GRAY.0);
    assert!(sys::f2s_log_level::F2S_LOG_NONE.0 == 0);
    assert!(sys::f2s_log_level::F2S_LOG_ERROR.0 == 1);
    assert!(sys::f2s_log_level::F2S_LOG_WARNING.0 == 2);
    assert!(sys::f2s_log_level::F2S_LOG_INFO.0 == 3);
    assert!(sys::f2s_log_level::F2S_LOG_DEBUG.0 == 4);
};

/// libfreenect2's version, e.g. "0.2.0".
pub fn library_version() -> String {
    // SAFETY: f2s_version returns a pointer to a static NUL-terminated string.
    let version = unsafe { std::ffi::CStr::from_ptr(sys::f2s_version()) };
    version.to_string_lossy().into_owned()
}

/// Reads a string through a shim call that fills a caller buffer.
fn read_string(
    action: &'static str,
    serial: Option<&str>,
    mut call: impl FnMut(*mut c_char, usize, &mut usize) -> sys::f2s_status,
) -> Result<String, Kinect2Error> {
    let mut buffer = vec![0u8; 64];
    loop {
        let mut length = 0usize;
        let status = call(buffer.as_mut_ptr().cast(), buffer.len(), &mut length);
        if status == sys::f2s_status::F2S_ERR_BUFFER_TOO_SMALL && length + 1 > buffer.len() {
            buffer.resize(length + 1, 0);
            continue;
        }
        check(status, action, serial)?;
        buffer.truncate(length.min(buffer.len()));
        return Ok(String::from_utf8_lossy(&buffer).into_owned());
    }
}

impl Pipeline {
    fn raw(self) -> sys::f2s_pipeline {
        match self {
            Self::Default => sys::f2s_pipeline::F2S_PIPELINE_DEFAULT,
            Self::Cpu => sys::f2s_pipeline::F2S_PIPELINE_CPU,
            Self::OpenCl => sys::f2s_pipeline::F2S_PIPELINE_OPENCL,
            Self::OpenClKde => sys::f2s_pipeline::F2S_PIPELINE_OPENCL_KDE,
            Self::Cuda => sys::f2s_pipeline::F2S_PIPELINE_CUDA,
            Self::CudaKde => sys::f2s_pipeline::F2S_PIPELINE_CUDA_KDE,
            Self::OpenGl => sys::f2s_pipeline::F2S_PIPELINE_OPENGL,
        }
    }

    /// True when the installed libfreenect2 was built with this pipeline.
    pub fn is_available(self) -> bool {
        // SAFETY: a pure query of compile-time flags; any enum value is accepted.
        unsafe { sys::f2s_pipeline_available(self.raw()) != 0 }
    }

    /// The pipelines the installed libfreenect2 offers.
    pub fn available() -> Vec<Pipeline> {
        Self::ALL.into_iter().filter(|p| p.is_available()).collect()
    }
}

impl DepthConfig {
    /// libfreenect2's own defaults (`Config()`), as the library reports
    /// them: the binding's tests check [`DepthConfig::default`] against
    /// them.
    pub fn from_library() -> Self {
        let mut raw = sys::f2s_config::default();
        // SAFETY: `raw` is a valid, writable f2s_config.
        unsafe { sys::f2s_config_default(&mut raw) };
        Self {
            min_depth_m: raw.min_depth_m,
            max_depth_m: raw.max_depth_m,
            bilateral_filter: raw.bilateral_filter != 0,
            edge_aware_filter: raw.edge_aware_filter != 0,
        }
    }
}

impl IrParams {
    pub(crate) fn to_raw(self) -> sys::f2s_ir_params {
        sys::f2s_ir_params {
            fx: self.fx,
            fy: self.fy,
            cx: self.cx,
            cy: self.cy,
            k1: self.k1,
            k2: self.k2,
            k3: self.k3,
            p1: self.p1,
            p2: self.p2,
        }
    }

    fn from_raw(raw: &sys::f2s_ir_params) -> Self {
        Self {
            fx: raw.fx,
            fy: raw.fy,
            cx: raw.cx,
            cy: raw.cy,
            k1: raw.k1,
            k2: raw.k2,
            k3: raw.k3,
            p1: raw.p1,
            p2: raw.p2,
        }
    }
}

impl ColorParams {
    /// Parameters in the shim's layout (a stored calibration, or a test).
    pub fn from_raw(raw: sys::f2s_color_params) -> Self {
        Self {
            fx: raw.fx,
            fy: raw.fy,
            cx: raw.cx,
            cy: raw.cy,
            shift_d: raw.shift_d,
            shift_m: raw.shift_m,
            mx_x3y0: raw.mx_x3y0,
            mx_x0y3: raw.mx_x0y3,
            mx_x2y1: raw.mx_x2y1,
            mx_x1y2: raw.mx_x1y2,
            mx_x2y0: raw.mx_x2y0,
            mx_x0y2: raw.mx_x0y2,
            mx_x1y1: raw.mx_x1y1,
            mx_x1y0: raw.mx_x1y0,
            mx_x0y1: raw.mx_x0y1,
            mx_x0y0: raw.mx_x0y0,
            my_x3y0: raw.my_x3y0,
            my_x0y3: raw.my_x0y3,
            my_x2y1: raw.my_x2y1,
            my_x1y2: raw.my_x1y2,
            my_x2y0: raw.my_x2y0,
            my_x0y2: raw.my_x0y2,
            my_x1y1: raw.my_x1y1,
            my_x1y0: raw.my_x1y0,
            my_x0y1: raw.my_x0y1,
            my_x0y0: raw.my_x0y0,
        }
    }

    /// The parameters in the shim's layout.
    pub fn raw(&self) -> sys::f2s_color_params {
        sys::f2s_color_params {
            fx: self.fx,
            fy: self.fy,
            cx: self.cx,
            cy: self.cy,
            shift_d: self.shift_d,
            shift_m: self.shift_m,
            mx_x3y0: self.mx_x3y0,
            mx_x0y3: self.mx_x0y3,
            mx_x2y1: self.mx_x2y1,
            mx_x1y2: self.mx_x1y2,
            mx_x2y0: self.mx_x2y0,
            mx_x0y2: self.mx_x0y2,
            mx_x1y1: self.mx_x1y1,
            mx_x1y0: self.mx_x1y0,
            mx_x0y1: self.mx_x0y1,
            mx_x0y0: self.mx_x0y0,
            my_x3y0: self.my_x3y0,
            my_x0y3: self.my_x0y3,
            my_x2y1: self.my_x2y1,
            my_x1y2: self.my_x1y2,
            my_x2y0: self.my_x2y0,
            my_x0y2: self.my_x0y2,
            my_x1y1: self.my_x1y1,
            my_x1y0: self.my_x1y0,
            my_x0y1: self.my_x0y1,
            my_x0y0: self.my_x0y0,
        }
    }
}

/// Owns a libfreenect2::Freenect2 and knows which of its devices are open.
struct ContextState {
    handle: NonNull<sys::f2s_context>,
    /// Serials of the devices opened through this context and not yet
    /// dropped: libfreenect2's openDevice returns the *same* device object
    /// for a second open, which two owners would then both free.
    open: OpenSerials,
}

// SAFETY: libfreenect2::Freenect2 has no thread affinity (its USB event thread
// is internal); every use goes through the Mutex in `Context` (devices lock
// it too), so it is never used from two threads at once.
unsafe impl Send for ContextState {}

impl Drop for ContextState {
    fn drop(&mut self) {
        // SAFETY: the pointer came from f2s_context_new and is freed once,
        // here. Every Device holds an Arc to this state, so no device of
        // this context is alive any more.
        unsafe { sys::f2s_context_free(self.handle.as_ptr()) };
    }
}

type SharedContext = Arc<Mutex<ContextState>>;

fn lock(context: &SharedContext) -> MutexGuard<'_, ContextState> {
    // A panic while holding the lock cannot leave the C++ object half
    // updated (the shim catches everything), and the serial set is only
    // changed by single inserts/removes, so a poisoned lock is usable.
    context
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// The serials of the enumerated devices (the caller holds the lock).
fn enumerate_locked(state: &ContextState) -> Result<Vec<String>, Kinect2Error> {
    let context = state.handle.as_ptr();
    let mut count = 0i32;
    log::clear_last_problem();
    // SAFETY: `context` is alive (the caller holds its lock) and `count` is
    // writable.
    check(
        unsafe { sys::f2s_context_enumerate(context, &mut count) },
        "enumerate USB devices",
        None,
    )?;
    (0..count)
        .map(|index| {
            read_string("read a device serial", None, |buffer, capacity, length| {
                // SAFETY: `context` is alive; `buffer` holds `capacity`
                // writable bytes; `length` is writable.
                unsafe { sys::f2s_context_serial(context, index, buffer, capacity, length) }
            })
        })
        .collect()
}

/// The libfreenect2 context: enumerates and opens devices. One context may
/// be shared between threads (clones share it); every call into
/// libfreenect2 through it or its devices is serialised by one lock.
#[derive(Clone)]
pub struct Context {
    inner: SharedContext,
}

impl Context {
    /// Creates a context (and libfreenect2's USB context). Routes
    /// libfreenect2's log into `tracing` on first use.
    pub fn new() -> Result<Self, Kinect2Error> {
        log::install();
        let action = "create the libfreenect2 context";
        let mut raw = std::ptr::null_mut();
        // SAFETY: `raw` is a valid out-pointer.
        check(unsafe { sys::f2s_context_new(&mut raw) }, action, None)?;
        let handle = non_null(raw, action, None)?;
        Ok(Self {
            inner: Arc::new(Mutex::new(ContextState {
                handle,
                open: OpenSerials::default(),
            })),
        })
    }

    /// Re-enumerates the USB bus and returns the serials of the connected
    /// Kinect v2 devices, in enumeration order.
    pub fn enumerate(&self) -> Result<Vec<String>, Kinect2Error> {
        enumerate_locked(&lock(&self.inner))
    }

    /// True while a [`Device`] with this serial, opened through this
    /// context, is alive.
    pub fn is_open(&self, serial: &str) -> bool {
        lock(&self.inner).open.is_open(serial)
    }

    /// Opens a device with a depth pipeline. `gpu_device` picks the OpenCL
    /// or CUDA device (`None`: libfreenect2's default). A device that is
    /// already open through this context is refused
    /// ([`Kinect2Error::AlreadyOpen`]), and so is one that another process
    /// has open ([`Kinect2Error::Locked`], naming its PID): the device's
    /// [`DeviceLock`] is taken before libfreenect2 resets it, and held as long
    /// as the [`Device`] lives. A device other than the one asked for
    /// (libfreenect2 re-opens by index when the wanted one vanishes during
    /// its reset) is closed again: [`Kinect2Error::SerialMismatch`].
    pub fn open(
        &self,
        selector: &DeviceSelector,
        pipeline: Pipeline,
        gpu_device: Option<u32>,
    ) -> Result<Device, Kinect2Error> {
        check_pipeline_available(pipeline)?;
        // A known serial is locked before anything touches the USB bus.
        let mut device_lock = match selector {
            DeviceSelector::Serial(serial) => Some(DeviceLock::acquire(LOCK_KIND, serial)?),
            _ => None,
        };
        // One lock from enumeration to the open: nothing else in this
        // process can open or free a device in between.
        let mut state = lock(&self.inner);
        let serial = choose_serial(selector, enumerate_locked(&state)?)?;
        let c_serial = std::ffi::CString::new(serial.as_str())
            .map_err(|_| Kinect2Error::InvalidSerial(serial.clone()))?;
        state.open.claim(&serial)?;
        if device_lock.is_none() {
            match DeviceLock::acquire(LOCK_KIND, &serial) {
                Ok(taken) => device_lock = Some(taken),
                Err(err) => {
                    state.open.release(&serial);
                    return Err(err.into());
                }
            }
        }
        let handle = match open_claimed(&state, &c_serial, &serial, pipeline, gpu_device) {
            Ok(handle) => handle,
            Err(err) => {
                state.open.release(&serial);
                return Err(err);
            }
        };
        drop(state);
        let device = Device {
            handle,
            context: Arc::clone(&self.inner),
            serial,
            pipeline,
            listener: None,
            retired_listeners: Vec::new(),
            streaming: false,
            _lock: device_lock,
        };
        // Dropping a mismatched device closes it (and releases the claim).
        check_opened_serial(&device.serial, &device.opened_serial()?)?;
        Ok(device)
    }
}

/// [`Kinect2Error::PipelineUnavailable`] unless this libfreenect2 build has
/// `pipeline`, naming the ones it has.
fn check_pipeline_available(pipeline: Pipeline) -> Result<(), Kinect2Error> {
    if pipeline.is_available() {
        return Ok(());
    }
    Err(Kinect2Error::PipelineUnavailable {
        pipeline: pipeline.name(),
        available: Pipeline::available()
            .iter()
            .map(|p| p.name())
            .collect::<Vec<_>>()
            .join(", "),
    })
}

/// The serial `selector` picks among the connected `serials` (enumeration
/// order), or why none fits.
fn choose_serial(selector: &DeviceSelector, serials: Vec<String>) -> Result<String, Kinect2Error> {
    if serials.is_empty() {
        return Err(Kinect2Error::NoDevice {
            version: library_version(),
            libfreenect2_log: log::take_last_problem(),
        });
    }
    match selector {
        DeviceSelector::First => Ok(serials[0].clone()),
        DeviceSelector::Index(index) => match serials.get(*index as usize) {
            Some(serial) => Ok(serial.clone()),
            None => Err(Kinect2Error::IndexOutOfRange {
                index: *index,
                count: u32::try_from(serials.len()).unwrap_or(u32::MAX),
            }),
        },
        DeviceSelector::Serial(wanted) => {
            if serials.contains(wanted) {
                Ok(wanted.clone())
            } else {
                Err(Kinect2Error::SerialNotFound {
                    serial: wanted.clone(),
                    connected: serials,
                })
            }
        }
    }
}

/// Opens the device with serial `serial` (already claimed in `state`) with a
/// depth `pipeline` on GPU `gpu_device` (`None`: libfreenect2's default).
fn open_claimed(
    state: &ContextState,
    c_serial: &std::ffi::CStr,
    serial: &str,
    pipeline: Pipeline,
    gpu_device: Option<u32>,
) -> Result<NonNull<sys::f2s_device>, Kinect2Error> {
    let gpu = gpu_device.map_or(-1, |id| i32::try_from(id).unwrap_or(i32::MAX));
    let mut raw = std::ptr::null_mut();
    log::clear_last_problem();
    // SAFETY: the context is alive (the caller holds its lock, which `state`
    // borrows from); `c_serial` is a NUL-terminated string; `raw` is a valid
    // out-pointer. The shim hands the pipeline's ownership to libfreenect2.
    // Opening by serial (not by the index enumerated before) cannot pick
    // another device should the bus change underneath.
    let status = unsafe {
        sys::f2s_context_open_serial(
            state.handle.as_ptr(),
            c_serial.as_ptr(),
            pipeline.raw(),
            gpu,
            &mut raw,
        )
    };
    check(status, "open the device", Some(serial))
        .and_then(|()| non_null(raw, "open the device", Some(serial)))
}

/// Which streams to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Streams {
    pub color: bool,
    pub depth: bool,
}

impl Streams {
    pub const DEPTH: Streams = Streams {
        color: false,
        depth: true,
    };
    pub const DEPTH_AND_COLOR: Streams = Streams {
        color: true,
        depth: true,
    };

    fn frame_types(self) -> u32 {
        let mut types = 0;
        if self.color {
            types |= sys::f2s_frame_type::F2S_FRAME_COLOR.0;
        }
        // IR is decoded with depth but nothing here uses it: not taking it
        // lets libfreenect2 reuse its IR frame instead of allocating one
        // for every frame set.
        if self.depth {
            types |= sys::f2s_frame_type::F2S_FRAME_DEPTH.0;
        }
        types
    }
}

/// Owns the shim's frame listener (a mutex and condition variable; its waits
/// honour their timeout whatever threading libfreenect2 was built with).
struct Listener {
    handle: NonNull<sys::f2s_listener>,
    types: u32,
}

impl Listener {
    fn new(types: u32, serial: &str) -> Result<Self, Kinect2Error> {
        let action = "create a frame listener";
        let mut raw = std::ptr::null_mut();
        // SAFETY: `raw` is a valid out-pointer.
        check(
            unsafe { sys::f2s_listener_new(types, &mut raw) },
            action,
            Some(serial),
        )?;
        let handle = non_null(raw, action, Some(serial))?;
        Ok(Self { handle, types })
    }
}

// SAFETY: the shim's listener synchronises internally (a mutex and a
// condition variable) between libfreenect2's threads and the waiting one.
unsafe impl Send for Listener {}

impl Drop for Listener {
    fn drop(&mut self) {
        // SAFETY: the pointer came from f2s_listener_new and is freed once.
        // The Device drops its listeners only after freeing the device, so
        // libfreenect2 no longer holds it.
        unsafe { sys::f2s_listener_free(self.handle.as_ptr()) };
    }
}

/// An opened Kinect v2.
pub struct Device {
    handle: NonNull<sys::f2s_device>,
    context: SharedContext,
    serial: String,
    pipeline: Pipeline,
    /// The listener of the current streams.
    listener: Option<Listener>,
    /// Listeners of earlier starts: libfreenect2 may still deliver to them
    /// until the device is freed.
    retired_listeners: Vec<Listener>,
    streaming: bool,
    /// The cross-process lock of the serial; released after the device is
    /// freed (fields drop after `Drop::drop`).
    _lock: Option<DeviceLock>,
}

// SAFETY: a Freenect2Device has no thread affinity; all mutation goes through
// `&mut self`, and every call into libfreenect2 on it (which may touch its
// context) holds the context's Mutex. Waiting touches only our own listener,
// which synchronises internally.
unsafe impl Send for Device {}

impl fmt::Debug for Device {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Device")
            .field("serial", &self.serial)
            .field("pipeline", &self.pipeline)
            .field("streaming", &self.streaming)
            .finish_non_exhaustive()
    }
}

impl Device {
    pub fn serial(&self) -> &str {
        &self.serial
    }

    pub fn pipeline(&self) -> Pipeline {
        self.pipeline
    }

    pub fn is_streaming(&self) -> bool {
        self.streaming
    }

    /// The serial libfreenect2's device object reports (the one it really
    /// opened).
    pub fn opened_serial(&self) -> Result<String, Kinect2Error> {
        let _context = lock(&self.context);
        let device = self.handle.as_ptr();
        read_string(
            "read the serial of the opened device",
            Some(&self.serial),
            |buffer, capacity, length| {
                // SAFETY: `device` is open; `buffer` holds `capacity` writable bytes.
                unsafe { sys::f2s_device_serial(device, buffer, capacity, length) }
            },
        )
    }

    pub fn firmware_version(&mut self) -> Result<String, Kinect2Error> {
        let _context = lock(&self.context);
        let device = self.handle.as_ptr();
        read_string(
            "read the firmware version",
            Some(&self.serial),
            |buffer, capacity, length| {
                // SAFETY: `device` is open; `buffer` holds `capacity` writable bytes.
                unsafe { sys::f2s_device_firmware(device, buffer, capacity, length) }
            },
        )
    }

    /// Applies a depth configuration; only before [`Device::start`] or after
    /// [`Device::stop`].
    pub fn set_depth_config(&mut self, config: &DepthConfig) -> Result<(), Kinect2Error> {
        let raw = sys::f2s_config {
            min_depth_m: config.min_depth_m,
            max_depth_m: config.max_depth_m,
            bilateral_filter: i32::from(config.bilateral_filter),
            edge_aware_filter: i32::from(config.edge_aware_filter),
        };
        let _context = lock(&self.context);
        // SAFETY: the device is open and `raw` is a valid config.
        let status = unsafe { sys::f2s_device_set_config(self.handle.as_ptr(), &raw) };
        check(status, "configure depth processing", Some(&self.serial))
    }

    /// The IR camera's factory parameters. libfreenect2 reads them from the
    /// device during [`Device::start`]; before that they are placeholders.
    pub fn ir_params(&mut self) -> Result<IrParams, Kinect2Error> {
        let mut raw = sys::f2s_ir_params::default();
        let _context = lock(&self.context);
        // SAFETY: the device is open and `raw` is writable.
        let status = unsafe { sys::f2s_device_ir_params(self.handle.as_ptr(), &mut raw) };
        check(status, "read the IR camera parameters", Some(&self.serial))?;
        Ok(IrParams::from_raw(&raw))
    }

    /// The colour camera's factory parameters (valid after start, as above).
    pub fn color_params(&mut self) -> Result<ColorParams, Kinect2Error> {
        let mut raw = sys::f2s_color_params::default();
        let _context = lock(&self.context);
        // SAFETY: the device is open and `raw` is writable.
        let status = unsafe { sys::f2s_device_color_params(self.handle.as_ptr(), &mut raw) };
        check(
            status,
            "read the colour camera parameters",
            Some(&self.serial),
        )?;
        Ok(ColorParams::from_raw(raw))
    }

    /// Starts the streams (depth only, or depth and colour).
    pub fn start(&mut self, streams: Streams) -> Result<(), Kinect2Error> {
        if self.streaming {
            self.stop()?;
        }
        let types = streams.frame_types();
        let _context = lock(&self.context);
        if self.listener.as_ref().map(|l| l.types) != Some(types) {
            let listener = Listener::new(types, &self.serial)?;
            // SAFETY: the device is open and not streaming; the listener
            // lives until after the device is freed (see Drop).
            let status = unsafe {
                sys::f2s_device_set_listener(self.handle.as_ptr(), listener.handle.as_ptr())
            };
            check(status, "attach the frame listener", Some(&self.serial))?;
            if let Some(old) = self.listener.replace(listener) {
                self.retired_listeners.push(old);
            }
        }
        log::clear_last_problem();
        // SAFETY: the device is open with a listener attached.
        let status = unsafe {
            sys::f2s_device_start(
                self.handle.as_ptr(),
                i32::from(streams.color),
                i32::from(streams.depth),
            )
        };
        check(status, "start the streams", Some(&self.serial))?;
        self.streaming = true;
        Ok(())
    }

    /// Stops the streams. The listener stays attached (and alive) until the
    /// device is dropped.
    pub fn stop(&mut self) -> Result<(), Kinect2Error> {
        if !self.streaming {
            return Ok(());
        }
        self.streaming = false;
        log::clear_last_problem();
        let _context = lock(&self.context);
        // SAFETY: the device is open.
        let status = unsafe { sys::f2s_device_stop(self.handle.as_ptr()) };
        check(status, "stop the streams", Some(&self.serial))
    }

    /// Colour and depth frames libfreenect2 has delivered since the streams
    /// first started, taken or not: `(colour, depth)`, `(0, 0)` before.
    pub fn frame_counts(&self) -> (u64, u64) {
        let Some(listener) = self.listener.as_ref() else {
            return (0, 0);
        };
        let (mut color, mut depth) = (0u64, 0u64);
        // SAFETY: the listener is alive; both out-pointers are writable. The
        // shim reads the counters under the listener's own mutex.
        let status =
            unsafe { sys::f2s_listener_counts(listener.handle.as_ptr(), &mut color, &mut depth) };
        if status == sys::f2s_status::F2S_OK {
            (color, depth)
        } else {
            (0, 0)
        }
    }

    /// Waits up to `timeout` for a complete frame set; `Ok(None)` on timeout.
    pub fn wait_for_frames(
        &mut self,
        timeout: Duration,
    ) -> Result<Option<FrameSet<'_>>, Kinect2Error> {
        let Some(listener) = self.listener.as_mut() else {
            return Err(Kinect2Error::Operation {
                action: "wait for frames before starting the streams",
                serial: Some(self.serial.clone()),
                status: ShimStatus(sys::f2s_status::F2S_ERR_NO_FRAME.0),
                exception: None,
                libfreenect2_log: None,
            });
        };
        let timeout_ms = i32::try_from(timeout.as_millis()).unwrap_or(i32::MAX);
        // SAFETY: the listener is alive; it holds no frames that a FrameSet
        // still borrows (a FrameSet borrows `self` mutably).
        let status = unsafe { sys::f2s_listener_wait(listener.handle.as_ptr(), timeout_ms) };
        if status == sys::f2s_status::F2S_ERR_TIMEOUT {
            return Ok(None);
        }
        check(status, "wait for frames", Some(&self.serial))?;
        Ok(Some(FrameSet {
            listener: listener.handle,
            serial: &self.serial,
            _device: PhantomData,
        }))
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        if self.streaming {
            if let Err(err) = self.stop() {
                tracing::warn!(error = %err, "stopping the Kinect v2 streams failed");
            }
        }
        let mut context = lock(&self.context);
        // SAFETY: the pointer came from f2s_context_open_* and is freed once,
        // here, while its context is alive (we hold an Arc and its lock). The
        // destructor closes the device and joins its processing threads, so
        // afterwards nothing delivers to our listeners.
        unsafe { sys::f2s_device_free(self.handle.as_ptr()) };
        context.open.release(&self.serial);
        drop(context);
        // Only now may the listeners go.
        self.listener = None;
        self.retired_listeners.clear();
    }
}

/// A complete set of frames (depth, and colour when streaming it), held
/// until dropped.
pub struct FrameSet<'d> {
    listener: NonNull<sys::f2s_listener>,
    serial: &'d str,
    _device: PhantomData<&'d mut Device>,
}

impl FrameSet<'_> {
    fn frame(&self, kind: sys::f2s_frame_type) -> Option<FrameView<'_>> {
        let mut raw = sys::f2s_frame_view::default();
        // SAFETY: the listener is alive and holds this set's frames while
        // `self` exists; `raw` is writable.
        let status = unsafe { sys::f2s_listener_frame(self.listener.as_ptr(), kind, &mut raw) };
        if status != sys::f2s_status::F2S_OK || raw.data.is_null() {
            return None;
        }
        let len = raw
            .width
            .checked_mul(raw.height)?
            .checked_mul(raw.bytes_per_pixel)?;
        // SAFETY: libfreenect2 guarantees that `data` points to `width *
        // height * bytes_per_pixel` readable bytes that stay valid and
        // unchanged until this set releases them (its drop), which the
        // returned view, borrowing `self`, cannot outlive.
        let data = unsafe { std::slice::from_raw_parts(raw.data, len) };
        let view = FrameView::from_bytes(
            raw.width,
            raw.height,
            raw.bytes_per_pixel,
            FrameFormat::from_code(raw.format),
            data,
        )?;
        Some(view.with_metadata(FrameMetadata {
            status: raw.status,
            timestamp: raw.timestamp,
            sequence: raw.sequence,
            exposure: raw.exposure,
            gain: raw.gain,
            gamma: raw.gamma,
        }))
    }

    /// The depth frame: 512 x 424 float millimetres (mirrored, distorted).
    pub fn depth(&self) -> Option<FrameView<'_>> {
        self.frame(sys::f2s_frame_type::F2S_FRAME_DEPTH)
    }

    /// The colour frame: 1920 x 1080, 4 bytes per pixel (BGRX or RGBX).
    pub fn color(&self) -> Option<FrameView<'_>> {
        self.frame(sys::f2s_frame_type::F2S_FRAME_COLOR)
    }

    /// The serial of the device the set came from.
    pub fn serial(&self) -> &str {
        self.serial
    }
}

impl Drop for FrameSet<'_> {
    fn drop(&mut self) {
        // SAFETY: the listener is alive (the device that owns it is borrowed
        // for our lifetime); releasing gives the frames back to libfreenect2
        // and no FrameView outlives `self`.
        unsafe { sys::f2s_listener_release(self.listener.as_ptr()) };
    }
}

impl FrameView<'_> {
    /// The view in the shim's layout, for a call into the shim.
    pub(crate) fn raw(&self) -> sys::f2s_frame_view {
        let metadata = self.metadata();
        sys::f2s_frame_view {
            width: self.width(),
            height: self.height(),
            bytes_per_pixel: self.bytes_per_pixel(),
            data: self.data().as_ptr(),
            timestamp: metadata.timestamp,
            sequence: metadata.sequence,
            exposure: metadata.exposure,
            gain: metadata.gain,
            gamma: metadata.gamma,
            status: metadata.status,
            format: self.format().code(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shim's own listener returns from a wait when nothing arrives
    /// (libfreenect2's SyncMultiFrameListener, built without ENABLE_CXX11,
    /// would block for good), and holds no frame afterwards.
    #[test]
    fn a_wait_without_frames_times_out() {
        let listener =
            Listener::new(Streams::DEPTH_AND_COLOR.frame_types(), "test").expect("listener");
        for timeout_ms in [0, 1, 20] {
            // SAFETY: the listener is alive and holds no frames.
            let status = unsafe { sys::f2s_listener_wait(listener.handle.as_ptr(), timeout_ms) };
            assert_eq!(status, sys::f2s_status::F2S_ERR_TIMEOUT);
            let mut view = sys::f2s_frame_view::default();
            // SAFETY: as above; `view` is writable.
            let status = unsafe {
                sys::f2s_listener_frame(
                    listener.handle.as_ptr(),
                    sys::f2s_frame_type::F2S_FRAME_DEPTH,
                    &mut view,
                )
            };
            assert_eq!(status, sys::f2s_status::F2S_ERR_NO_FRAME);
        }
    }

    #[test]
    fn a_context_tracks_nothing_open_at_first() {
        let context = Context::new().expect("libfreenect2 context");
        assert!(!context.is_open("012345678912"));
    }
}

/*
 * A small C interface over libfreenect2's C++ API, for bindgen.
 *
 * Every function catches C++ exceptions and reports them as F2S_ERR_EXCEPTION,
 * so nothing unwinds into Rust; f2s_take_exception gives the exception's text
 * (what()) to the thread that made the call. Handles are opaque; each `*_new`/`*_open`
 * has a matching `*_free`. Nothing here keeps global state except the log
 * forwarding installed by f2s_set_log_callback.
 *
 * Ownership rules (the safe Rust wrapper enforces them):
 * - a device must be freed before the context that opened it;
 * - a listener given to a device must outlive the device (free the device
 *   first: its destructor stops the streams and joins the processing threads);
 * - frame views returned by f2s_listener_frame are valid until
 *   f2s_listener_release or the next f2s_listener_wait on that listener;
 * - opening a device that is already open returns libfreenect2's existing
 *   device object again: never free it twice (the Rust layer refuses a
 *   second open of a serial).
 *
 * The listener is the shim's own (std::mutex + std::condition_variable), not
 * libfreenect2's SyncMultiFrameListener, whose timed wait blocks for good
 * unless libfreenect2 was built with ENABLE_CXX11.
 */
#ifndef SLOPE_FREENECT2_SHIM_H
#define SLOPE_FREENECT2_SHIM_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum f2s_status {
  F2S_OK = 0,
  F2S_ERR_NULL_ARGUMENT = 1,
  F2S_ERR_NOT_FOUND = 2,
  F2S_ERR_OPEN_FAILED = 3,
  F2S_ERR_PIPELINE_UNAVAILABLE = 4,
  F2S_ERR_START_FAILED = 5,
  F2S_ERR_STOP_FAILED = 6,
  F2S_ERR_CLOSE_FAILED = 7,
  F2S_ERR_TIMEOUT = 8,
  F2S_ERR_NO_FRAME = 9,
  F2S_ERR_BAD_SIZE = 10,
  F2S_ERR_BUFFER_TOO_SMALL = 11,
  F2S_ERR_EXCEPTION = 12
} f2s_status;

/* Depth packet pipelines. Which ones exist depends on how libfreenect2 was built. */
typedef enum f2s_pipeline {
  F2S_PIPELINE_DEFAULT = 0,
  F2S_PIPELINE_CPU = 1,
  F2S_PIPELINE_OPENCL = 2,
  F2S_PIPELINE_OPENCL_KDE = 3,
  F2S_PIPELINE_CUDA = 4,
  F2S_PIPELINE_CUDA_KDE = 5,
  F2S_PIPELINE_OPENGL = 6
} f2s_pipeline;

/* Same values as libfreenect2::Frame::Type; combine with | for a listener. */
typedef enum f2s_frame_type {
  F2S_FRAME_COLOR = 1,
  F2S_FRAME_IR = 2,
  F2S_FRAME_DEPTH = 4
} f2s_frame_type;

/* Same values as libfreenect2::Frame::Format. */
typedef enum f2s_frame_format {
  F2S_FORMAT_INVALID = 0,
  F2S_FORMAT_RAW = 1,
  F2S_FORMAT_FLOAT = 2,
  F2S_FORMAT_BGRX = 4,
  F2S_FORMAT_RGBX = 5,
  F2S_FORMAT_GRAY = 6
} f2s_frame_format;

/* Same values as libfreenect2::Logger::Level. */
typedef enum f2s_log_level {
  F2S_LOG_NONE = 0,
  F2S_LOG_ERROR = 1,
  F2S_LOG_WARNING = 2,
  F2S_LOG_INFO = 3,
  F2S_LOG_DEBUG = 4
} f2s_log_level;

typedef struct f2s_context f2s_context;
typedef struct f2s_device f2s_device;
typedef struct f2s_listener f2s_listener;
typedef struct f2s_registration f2s_registration;

/* libfreenect2::Freenect2Device::Config. */
typedef struct f2s_config {
  float min_depth_m;
  float max_depth_m;
  int32_t bilateral_filter;
  int32_t edge_aware_filter;
} f2s_config;

/* libfreenect2::Freenect2Device::IrCameraParams (pixel centres at +0.5). */
typedef struct f2s_ir_params {
  float fx, fy, cx, cy;
  float k1, k2, k3, p1, p2;
} f2s_ir_params;

/* libfreenect2::Freenect2Device::ColorCameraParams. */
typedef struct f2s_color_params {
  float fx, fy, cx, cy;
  float shift_d, shift_m;
  float mx_x3y0, mx_x0y3, mx_x2y1, mx_x1y2, mx_x2y0, mx_x0y2, mx_x1y1, mx_x1y0, mx_x0y1, mx_x0y0;
  float my_x3y0, my_x0y3, my_x2y1, my_x1y2, my_x2y0, my_x0y2, my_x1y1, my_x1y0, my_x0y1, my_x0y0;
} f2s_color_params;

/* A read-only view of a libfreenect2::Frame. */
typedef struct f2s_frame_view {
  size_t width;
  size_t height;
  size_t bytes_per_pixel;
  const uint8_t *data;
  uint32_t timestamp; /* 0.125 ms units */
  uint32_t sequence;
  float exposure;
  float gain;
  float gamma;
  uint32_t status;    /* 0 when the frame is good */
  uint32_t format;    /* an f2s_frame_format */
} f2s_frame_view;

/* An image buffer the caller owns: width x height pixels of bytes_per_pixel bytes. */
typedef struct f2s_image {
  size_t width;
  size_t height;
  size_t bytes_per_pixel;
  uint8_t *data;
} f2s_image;

typedef void (*f2s_log_fn)(int32_t level, const char *message, size_t length, void *user);

/* libfreenect2's version string, e.g. "0.2.0" (static storage). */
const char *f2s_version(void);

/* The text of the last exception a shim call on this thread caught (also in
 * the functions that return nothing, e.g. the *_free ones), then forgets it.
 * F2S_ERR_NOT_FOUND when there is none. */
f2s_status f2s_take_exception(char *buffer, size_t capacity, size_t *length);

/* For the tests of the exception path: throws std::runtime_error(message)
 * (an int when message is NULL) inside the shim's guard and returns what the
 * guard makes of it (F2S_ERR_EXCEPTION). */
f2s_status f2s_selftest_throw(const char *message);

/* 1 when this libfreenect2 was built with the pipeline, else 0. */
int32_t f2s_pipeline_available(f2s_pipeline pipeline);

/* Forwards libfreenect2's log lines at or above `level` to `callback` (NULL
 * restores libfreenect2's console logger). Not thread-safe: call once, early. */
f2s_status f2s_set_log_callback(f2s_log_fn callback, void *user, f2s_log_level level);

f2s_status f2s_context_new(f2s_context **out);
void f2s_context_free(f2s_context *context);
/* Re-enumerates the USB bus; writes the number of Kinect v2 devices. */
f2s_status f2s_context_enumerate(f2s_context *context, int32_t *count);
/* Serial of enumerated device `index` into `buffer` (NUL-terminated when it
 * fits); `length` receives the serial's length without the NUL. */
f2s_status f2s_context_serial(f2s_context *context, int32_t index, char *buffer, size_t capacity,
                              size_t *length);
/* `gpu_device` is the OpenCL/CUDA device id (-1: default); ignored otherwise. */
f2s_status f2s_context_open_index(f2s_context *context, int32_t index, f2s_pipeline pipeline,
                                  int32_t gpu_device, f2s_device **out);
f2s_status f2s_context_open_serial(f2s_context *context, const char *serial, f2s_pipeline pipeline,
                                   int32_t gpu_device, f2s_device **out);

/* Closes (stopping first if needed) and deletes the device. */
void f2s_device_free(f2s_device *device);
f2s_status f2s_device_serial(f2s_device *device, char *buffer, size_t capacity, size_t *length);
f2s_status f2s_device_firmware(f2s_device *device, char *buffer, size_t capacity, size_t *length);
f2s_status f2s_device_ir_params(f2s_device *device, f2s_ir_params *out);
f2s_status f2s_device_color_params(f2s_device *device, f2s_color_params *out);
f2s_status f2s_device_set_config(f2s_device *device, const f2s_config *config);
/* Gives `listener` both the colour and the IR/depth frames (NULL detaches). */
f2s_status f2s_device_set_listener(f2s_device *device, f2s_listener *listener);
f2s_status f2s_device_start(f2s_device *device, int32_t color, int32_t depth);
f2s_status f2s_device_stop(f2s_device *device);
f2s_status f2s_device_close(f2s_device *device);

/* libfreenect2's defaults: 0.5 m, 4.5 m, both filters on. */
void f2s_config_default(f2s_config *out);

/* `frame_types`: an | of f2s_frame_type. */
f2s_status f2s_listener_new(uint32_t frame_types, f2s_listener **out);
/* Releases held frames and deletes the listener. */
void f2s_listener_free(f2s_listener *listener);
/* Waits up to timeout_ms for a complete frame set (F2S_ERR_TIMEOUT if none).
 * Frames held from an earlier wait are released first. */
f2s_status f2s_listener_wait(f2s_listener *listener, int32_t timeout_ms);
/* Colour and depth frames libfreenect2 delivered to the listener so far,
 * taken or not (colour that flows while depth never comes is a depth
 * pipeline that could not initialise). */
f2s_status f2s_listener_counts(f2s_listener *listener, uint64_t *color, uint64_t *depth);
/* A view of one held frame (F2S_ERR_NO_FRAME if the set lacks it). */
f2s_status f2s_listener_frame(const f2s_listener *listener, f2s_frame_type type, f2s_frame_view *out);
/* Gives the held frames back to libfreenect2. */
void f2s_listener_release(f2s_listener *listener);

f2s_status f2s_registration_new(const f2s_ir_params *ir, const f2s_color_params *color,
                                f2s_registration **out);
void f2s_registration_free(f2s_registration *registration);
/* Registration::apply: `depth` (512x424 float mm) and `color` (1920x1080x4)
 * in, `undistorted` (512x424x4) and `registered` (512x424x4) out. The output
 * images must be 512x424 with 4 bytes per pixel. Reuses the registration's
 * own filter map and offset buffers (nothing is allocated per call), so one
 * registration must not be applied from two threads at once. */
f2s_status f2s_registration_apply(f2s_registration *registration, const f2s_frame_view *color,
                                  const f2s_frame_view *depth, f2s_image *undistorted,
                                  f2s_image *registered, int32_t enable_filter);
/* Registration::undistortDepth: depth in, undistorted depth (512x424x4) out. */
f2s_status f2s_registration_undistort(const f2s_registration *registration,
                                      const f2s_frame_view *depth, f2s_image *undistorted);

#ifdef __cplusplus
}
#endif

#endif /* SLOPE_FREENECT2_SHIM_H */

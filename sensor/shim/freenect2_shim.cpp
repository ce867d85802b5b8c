// The extern "C" shim over libfreenect2 declared in freenect2_shim.h.
//
// Each entry point validates its pointers, converts between the C structs and
// libfreenect2's classes, and catches every C++ exception: nothing may unwind
// across the C boundary into Rust.

#include "freenect2_shim.h"

#include <libfreenect2/config.h>
#include <libfreenect2/frame_listener_impl.h>
#include <libfreenect2/libfreenect2.hpp>
#include <libfreenect2/logger.h>
#include <libfreenect2/packet_pipeline.h>
#include <libfreenect2/registration.h>

#include <chrono>
#include <condition_variable>
#include <cstring>
#include <exception>
#include <map>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

// The text of the last exception a shim call on this thread caught, for
// f2s_take_exception (thread-local: another thread's failure never shows up
// in this thread's error).
thread_local std::string g_last_exception;

void remember_exception(const char *what) {
  try {
    g_last_exception = what ? what : "";
  } catch (...) {
    // No memory for the text: the status still says an exception happened.
  }
}

const size_t kDepthWidth = 512;
const size_t kDepthHeight = 424;
const size_t kColorWidth = 1920;
const size_t kColorHeight = 1080;
// Registration's filter map: the colour image with one row above and below.
const size_t kBigDepthHeight = 1082;

// Forwards libfreenect2's log lines to a C callback.
class CallbackLogger : public libfreenect2::Logger {
 public:
  CallbackLogger(f2s_log_fn callback, void *user, Level level) : callback_(callback), user_(user) {
    level_ = level;
  }
  virtual ~CallbackLogger() {}
  virtual void log(Level level, const std::string &message) {
    callback_(static_cast<int32_t>(level), message.data(), message.size(), user_);
  }

 private:
  f2s_log_fn callback_;
  void *user_;
};

libfreenect2::PacketPipeline *make_pipeline(f2s_pipeline pipeline, int32_t gpu_device) {
  (void)gpu_device;  // unused when no GPU pipeline is built in
  switch (pipeline) {
    case F2S_PIPELINE_DEFAULT:
      return 0;  // the caller uses libfreenect2's default pipeline
    case F2S_PIPELINE_CPU:
      return new libfreenect2::CpuPacketPipeline();
#ifdef LIBFREENECT2_WITH_OPENCL_SUPPORT
    case F2S_PIPELINE_OPENCL:
      return new libfreenect2::OpenCLPacketPipeline(gpu_device);
    case F2S_PIPELINE_OPENCL_KDE:
      return new libfreenect2::OpenCLKdePacketPipeline(gpu_device);
#endif
#ifdef LIBFREENECT2_WITH_CUDA_SUPPORT
    case F2S_PIPELINE_CUDA:
      return new libfreenect2::CudaPacketPipeline(gpu_device);
    case F2S_PIPELINE_CUDA_KDE:
      return new libfreenect2::CudaKdePacketPipeline(gpu_device);
#endif
#ifdef LIBFREENECT2_WITH_OPENGL_SUPPORT
    case F2S_PIPELINE_OPENGL:
      return new libfreenect2::OpenGLPacketPipeline();
#endif
    default:
      return 0;
  }
}

f2s_status copy_string(const std::string &value, char *buffer, size_t capacity, size_t *length) {
  if (!length) return F2S_ERR_NULL_ARGUMENT;
  *length = value.size();
  if (!buffer || capacity < value.size() + 1) return F2S_ERR_BUFFER_TOO_SMALL;
  std::memcpy(buffer, value.data(), value.size());
  buffer[value.size()] = '\0';
  return F2S_OK;
}

void to_c(const libfreenect2::Freenect2Device::IrCameraParams &p, f2s_ir_params *out) {
  out->fx = p.fx;
  out->fy = p.fy;
  out->cx = p.cx;
  out->cy = p.cy;
  out->k1 = p.k1;
  out->k2 = p.k2;
  out->k3 = p.k3;
  out->p1 = p.p1;
  out->p2 = p.p2;
}

libfreenect2::Freenect2Device::IrCameraParams from_c(const f2s_ir_params &p) {
  libfreenect2::Freenect2Device::IrCameraParams out;
  out.fx = p.fx;
  out.fy = p.fy;
  out.cx = p.cx;
  out.cy = p.cy;
  out.k1 = p.k1;
  out.k2 = p.k2;
  out.k3 = p.k3;
  out.p1 = p.p1;
  out.p2 = p.p2;
  return out;
}

// Field-by-field so that a reordering in either struct cannot go unnoticed.
#define F2S_COLOR_FIELDS(X)                                                                      \
  X(fx) X(fy) X(cx) X(cy) X(shift_d) X(shift_m) X(mx_x3y0) X(mx_x0y3) X(mx_x2y1) X(mx_x1y2)     \
  X(mx_x2y0) X(mx_x0y2) X(mx_x1y1) X(mx_x1y0) X(mx_x0y1) X(mx_x0y0) X(my_x3y0) X(my_x0y3)       \
  X(my_x2y1) X(my_x1y2) X(my_x2y0) X(my_x0y2) X(my_x1y1) X(my_x1y0) X(my_x0y1) X(my_x0y0)

void to_c(const libfreenect2::Freenect2Device::ColorCameraParams &p, f2s_color_params *out) {
#define F2S_COPY(name) out->name = p.name;
  F2S_COLOR_FIELDS(F2S_COPY)
#undef F2S_COPY
}

libfreenect2::Freenect2Device::ColorCameraParams from_c(const f2s_color_params &p) {
  libfreenect2::Freenect2Device::ColorCameraParams out;
#define F2S_COPY(name) out.name = p.name;
  F2S_COLOR_FIELDS(F2S_COPY)
#undef F2S_COPY
  return out;
}

bool view_has_size(const f2s_frame_view *view, size_t width, size_t height, size_t bpp) {
  return view && view->data && view->width == width && view->height == height &&
         view->bytes_per_pixel == bpp;
}

bool image_has_size(const f2s_image *image, size_t width, size_t height, size_t bpp) {
  return image && image->data && image->width == width && image->height == height &&
         image->bytes_per_pixel == bpp;
}

// A non-owning libfreenect2::Frame over a view's pixels (Registration only
// reads its inputs, so casting away const never leads to a write).
#define F2S_WRAP_VIEW(name, view)                                                   \
  libfreenect2::Frame name((view)->width, (view)->height, (view)->bytes_per_pixel, \
                           const_cast<unsigned char *>((view)->data));             \
  name.format = static_cast<libfreenect2::Frame::Format>((view)->format)

}  // namespace

struct f2s_context {
  libfreenect2::Freenect2 freenect2;
};

struct f2s_device {
  libfreenect2::Freenect2Device *device;
};

// Our own frame listener instead of libfreenect2::SyncMultiFrameListener:
// that one ignores the timeout of waitForNewFrame unless libfreenect2 was
// built with ENABLE_CXX11 (its TinyThread build waits forever), which would
// make frame timeouts, reconnection and stop requests impossible. This one
// always waits with std::condition_variable::wait_for.
//
// libfreenect2's colour and depth threads call onNewFrame concurrently; the
// waiting thread takes a complete set (one frame of every subscribed type)
// and holds it until release. Frames arriving while a set is held are given
// back to libfreenect2 (onNewFrame returns false), as libfreenect2's own
// listener does; a newer frame of a type replaces an older pending one.
class TimedFrameListener : public libfreenect2::FrameListener {
 public:
  explicit TimedFrameListener(unsigned int types)
      : subscribed_(types), ready_(0), released_(true), color_frames_(0), depth_frames_(0) {}

  virtual ~TimedFrameListener() {
    std::lock_guard<std::mutex> lock(mutex_);
    delete_all(pending_);
  }

  virtual bool onNewFrame(libfreenect2::Frame::Type type, libfreenect2::Frame *frame) {
    if ((subscribed_ & static_cast<unsigned int>(type)) == 0) return false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      // Counted whether or not the frame is taken: they tell whether a
      // stream flows at all (colour arriving while depth never does is a
      // depth pipeline that failed to initialise).
      if (type == libfreenect2::Frame::Color) ++color_frames_;
      if (type == libfreenect2::Frame::Depth) ++depth_frames_;
      if (!released_) return false;
      libfreenect2::FrameMap::iterator it = pending_.find(type);
      if (it != pending_.end()) {
        delete it->second;
        it->second = frame;
      } else {
        pending_[type] = frame;
      }
      ready_ |= static_cast<unsigned int>(type);
    }
    condition_.notify_one();
    return true;
  }

  // Moves a complete set into `out` (which must be empty); false when none
  // arrived within `timeout_ms`.
  bool wait(libfreenect2::FrameMap &out, int32_t timeout_ms) {
    std::unique_lock<std::mutex> lock(mutex_);
    const std::chrono::milliseconds timeout(timeout_ms < 0 ? 0 : timeout_ms);
    if (!condition_.wait_for(lock, timeout, [this] { return ready_ == subscribed_; })) {
      return false;
    }
    out.swap(pending_);
    pending_.clear();
    ready_ = 0;
    released_ = false;
    return true;
  }

  void counts(uint64_t *color, uint64_t *depth) {
    std::lock_guard<std::mutex> lock(mutex_);
    *color = color_frames_;
    *depth = depth_frames_;
  }

  // Deletes a set taken by wait and accepts frames again.
  void release(libfreenect2::FrameMap &frames) {
    delete_all(frames);
    std::lock_guard<std::mutex> lock(mutex_);
    released_ = true;
  }

 private:
  static void delete_all(libfreenect2::FrameMap &frames) {
    for (libfreenect2::FrameMap::iterator it = frames.begin(); it != frames.end(); ++it) {
      delete it->second;
    }
    frames.clear();
  }

  std::mutex mutex_;
  std::condition_variable condition_;
  libfreenect2::FrameMap pending_;
  const unsigned int subscribed_;
  unsigned int ready_;
  bool released_;
  uint64_t color_frames_;
  uint64_t depth_frames_;
};

struct f2s_listener {
  explicit f2s_listener(unsigned int types) : listener(types), holding(false) {}
  TimedFrameListener listener;
  libfreenect2::FrameMap frames;
  bool holding;
};

// The registration with the buffers Registration::apply would otherwise
// allocate (and free) on every call: the filter map (1920 x 1082 floats,
// 8.3 MB) and the colour offset of each depth pixel (512 x 424 ints).
struct f2s_registration {
  f2s_registration(const libfreenect2::Freenect2Device::IrCameraParams &ir,
                   const libfreenect2::Freenect2Device::ColorCameraParams &color)
      : registration(ir, color),
        big_depth(kColorWidth, kBigDepthHeight, 4),
        color_depth_map(kDepthWidth * kDepthHeight) {}
  libfreenect2::Registration registration;
  libfreenect2::Frame big_depth;
  std::vector<int> color_depth_map;
};

#define F2S_GUARD_BEGIN try {
#define F2S_GUARD_END                                   \
  }                                                     \
  catch (const std::exception &e) {                     \
    remember_exception(e.what());                       \
    return F2S_ERR_EXCEPTION;                           \
  }                                                     \
  catch (...) {                                         \
    remember_exception("an exception of unknown type"); \
    return F2S_ERR_EXCEPTION;                           \
  }

// For the functions that return nothing: keeps the text for
// f2s_take_exception and never unwinds.
#define F2S_VOID_CATCH                                  \
  catch (const std::exception &e) {                     \
    remember_exception(e.what());                       \
  }                                                     \
  catch (...) {                                         \
    remember_exception("an exception of unknown type"); \
  }

extern "C" {

const char *f2s_version(void) { return LIBFREENECT2_VERSION; }

f2s_status f2s_selftest_throw(const char *message) {
  F2S_GUARD_BEGIN
  if (message) throw std::runtime_error(message);
  throw 42;  // not a std::exception
  F2S_GUARD_END
}

f2s_status f2s_take_exception(char *buffer, size_t capacity, size_t *length) {
  if (!length) return F2S_ERR_NULL_ARGUMENT;
  *length = 0;
  if (g_last_exception.empty()) return F2S_ERR_NOT_FOUND;
  f2s_status status = copy_string(g_last_exception, buffer, capacity, length);
  if (status == F2S_OK) g_last_exception.clear();
  return status;
}

int32_t f2s_pipeline_available(f2s_pipeline pipeline) {
  switch (pipeline) {
    case F2S_PIPELINE_DEFAULT:
    case F2S_PIPELINE_CPU:
      return 1;
#ifdef LIBFREENECT2_WITH_OPENCL_SUPPORT
    case F2S_PIPELINE_OPENCL:
    case F2S_PIPELINE_OPENCL_KDE:
      return 1;
#endif
#ifdef LIBFREENECT2_WITH_CUDA_SUPPORT
    case F2S_PIPELINE_CUDA:
    case F2S_PIPELINE_CUDA_KDE:
      return 1;
#endif
#ifdef LIBFREENECT2_WITH_OPENGL_SUPPORT
    case F2S_PIPELINE_OPENGL:
      return 1;
#endif
    default:
      return 0;
  }
}

f2s_status f2s_set_log_callback(f2s_log_fn callback, void *user, f2s_log_level level) {
  F2S_GUARD_BEGIN
  if (!callback) {
    libfreenect2::setGlobalLogger(libfreenect2::createConsoleLoggerWithDefaultLevel());
    return F2S_OK;
  }
  // setGlobalLogger takes ownership and deletes the logger it replaces.
  libfreenect2::setGlobalLogger(
      new CallbackLogger(callback, user, static_cast<libfreenect2::Logger::Level>(level)));
  return F2S_OK;
  F2S_GUARD_END
}

f2s_status f2s_context_new(f2s_context **out) {
  if (!out) return F2S_ERR_NULL_ARGUMENT;
  *out = 0;
  F2S_GUARD_BEGIN
  *out = new f2s_context();
  return F2S_OK;
  F2S_GUARD_END
}

void f2s_context_free(f2s_context *context) {
  // A destructor that throws leaves nothing to recover; never unwind into Rust.
  try {
    delete context;
  }
  F2S_VOID_CATCH
}

f2s_status f2s_context_enumerate(f2s_context *context, int32_t *count) {
  if (!context || !count) return F2S_ERR_NULL_ARGUMENT;
  F2S_GUARD_BEGIN
  *count = context->freenect2.enumerateDevices();
  return F2S_OK;
  F2S_GUARD_END
}

f2s_status f2s_context_serial(f2s_context *context, int32_t index, char *buffer, size_t capacity,
                              size_t *length) {
  if (!context || !length) return F2S_ERR_NULL_ARGUMENT;
  F2S_GUARD_BEGIN
  std::string serial = context->freenect2.getDeviceSerialNumber(index);
  if (serial.empty()) return F2S_ERR_NOT_FOUND;
  return copy_string(serial, buffer, capacity, length);
  F2S_GUARD_END
}

static f2s_status open_device(f2s_context *context, const int32_t *index, const char *serial,
                              f2s_pipeline pipeline, int32_t gpu_device, f2s_device **out) {
  if (!context || !out) return F2S_ERR_NULL_ARGUMENT;
  *out = 0;
  if (!f2s_pipeline_available(pipeline)) return F2S_ERR_PIPELINE_UNAVAILABLE;
  F2S_GUARD_BEGIN
  // openDevice takes ownership of the pipeline, also when it fails.
  libfreenect2::PacketPipeline *packet_pipeline = make_pipeline(pipeline, gpu_device);
  libfreenect2::Freenect2Device *device = 0;
  if (index) {
    device = packet_pipeline ? context->freenect2.openDevice(*index, packet_pipeline)
                             : context->freenect2.openDevice(*index);
  } else {
    std::string wanted(serial);
    device = packet_pipeline ? context->freenect2.openDevice(wanted, packet_pipeline)
                             : context->freenect2.openDevice(wanted);
  }
  if (!device) return F2S_ERR_OPEN_FAILED;
  f2s_device *handle = new f2s_device();
  handle->device = device;
  *out = handle;
  return F2S_OK;
  F2S_GUARD_END
}

f2s_status f2s_context_open_index(f2s_context *context, int32_t index, f2s_pipeline pipeline,
                                  int32_t gpu_device, f2s_device **out) {
  return open_device(context, &index, 0, pipeline, gpu_device, out);
}

f2s_status f2s_context_open_serial(f2s_context *context, const char *serial, f2s_pipeline pipeline,
                                   int32_t gpu_device, f2s_device **out) {
  if (!serial) return F2S_ERR_NULL_ARGUMENT;
  return open_device(context, 0, serial, pipeline, gpu_device, out);
}

void f2s_device_free(f2s_device *device) {
  if (!device) return;
  // The destructor closes the device (stopping it first) and deletes its
  // pipeline, which joins the processing threads.
  try {
    delete device->device;
  }
  F2S_VOID_CATCH
  delete device;
}

f2s_status f2s_device_serial(f2s_device *device, char *buffer, size_t capacity, size_t *length) {
  if (!device) return F2S_ERR_NULL_ARGUMENT;
  F2S_GUARD_BEGIN
  return copy_string(device->device->getSerialNumber(), buffer, capacity, length);
  F2S_GUARD_END
}

f2s_status f2s_device_firmware(f2s_device *device, char *buffer, size_t capacity, size_t *length) {
  if (!device) return F2S_ERR_NULL_ARGUMENT;
  F2S_GUARD_BEGIN
  return copy_string(device->device->getFirmwareVersion(), buffer, capacity, length);
  F2S_GUARD_END
}

f2s_status f2s_device_ir_params(f2s_device *device, f2s_ir_params *out) {
  if (!device || !out) return F2S_ERR_NULL_ARGUMENT;
  F2S_GUARD_BEGIN
  to_c(device->device->getIrCameraParams(), out);
  return F2S_OK;
  F2S_GUARD_END
}

f2s_status f2s_device_color_params(f2s_device *device, f2s_color_params *out) {
  if (!device || !out) return F2S_ERR_NULL_ARGUMENT;
  F2S_GUARD_BEGIN
  to_c(device->device->getColorCameraParams(), out);
  return F2S_OK;
  F2S_GUARD_END
}

void f2s_config_default(f2s_config *out) {
  if (!out) return;
  try {
    libfreenect2::Freenect2Device::Config config;
    out->min_depth_m = config.MinDepth;
    out->max_depth_m = config.MaxDepth;
    out->bilateral_filter = config.EnableBilateralFilter ? 1 : 0;
    out->edge_aware_filter = config.EnableEdgeAwareFilter ? 1 : 0;
  } catch (...) {
    // The constructor only assigns four fields and cannot throw; fall back to
    // its documented values all the same.
    out->min_depth_m = 0.5f;
    out->max_depth_m = 4.5f;
    out->bilateral_filter = 1;
    out->edge_aware_filter = 1;
  }
}

f2s_status f2s_device_set_config(f2s_device *device, const f2s_config *config) {
  if (!device || !config) return F2S_ERR_NULL_ARGUMENT;
  F2S_GUARD_BEGIN
  libfreenect2::Freenect2Device::Config c;
  c.MinDepth = config->min_depth_m;
  c.MaxDepth = config->max_depth_m;
  c.EnableBilateralFilter = config->bilateral_filter != 0;
  c.EnableEdgeAwareFilter = config->edge_aware_filter != 0;
  device->device->setConfiguration(c);
  return F2S_OK;
  F2S_GUARD_END
}

f2s_status f2s_device_set_listener(f2s_device *device, f2s_listener *listener) {
  if (!device) return F2S_ERR_NULL_ARGUMENT;
  F2S_GUARD_BEGIN
  libfreenect2::FrameListener *target = listener ? &listener->listener : 0;
  device->device->setColorFrameListener(target);
  device->device->setIrAndDepthFrameListener(target);
  return F2S_OK;
  F2S_GUARD_END
}

f2s_status f2s_device_start(f2s_device *device, int32_t color, int32_t depth) {
  if (!device) return F2S_ERR_NULL_ARGUMENT;
  F2S_GUARD_BEGIN
  return device->device->startStreams(color != 0, depth != 0) ? F2S_OK : F2S_ERR_START_FAILED;
  F2S_GUARD_END
}

f2s_status f2s_device_stop(f2s_device *device) {
  if (!device) return F2S_ERR_NULL_ARGUMENT;
  F2S_GUARD_BEGIN
  return device->device->stop() ? F2S_OK : F2S_ERR_STOP_FAILED;
  F2S_GUARD_END
}

f2s_status f2s_device_close(f2s_device *device) {
  if (!device) return F2S_ERR_NULL_ARGUMENT;
  F2S_GUARD_BEGIN
  return device->device->close() ? F2S_OK : F2S_ERR_CLOSE_FAILED;
  F2S_GUARD_END
}

f2s_status f2s_listener_new(uint32_t frame_types, f2s_listener **out) {
  if (!out) return F2S_ERR_NULL_ARGUMENT;
  *out = 0;
  F2S_GUARD_BEGIN
  *out = new f2s_listener(frame_types);
  return F2S_OK;
  F2S_GUARD_END
}

void f2s_listener_release(f2s_listener *listener) {
  if (!listener || !listener->holding) return;
  // release() only deletes frames; nothing to recover.
  try {
    listener->listener.release(listener->frames);
  }
  F2S_VOID_CATCH
  listener->frames.clear();
  listener->holding = false;
}

void f2s_listener_free(f2s_listener *listener) {
  if (!listener) return;
  f2s_listener_release(listener);
  try {
    delete listener;
  }
  F2S_VOID_CATCH
}

f2s_status f2s_listener_wait(f2s_listener *listener, int32_t timeout_ms) {
  if (!listener) return F2S_ERR_NULL_ARGUMENT;
  f2s_listener_release(listener);
  F2S_GUARD_BEGIN
  if (!listener->listener.wait(listener->frames, timeout_ms)) return F2S_ERR_TIMEOUT;
  listener->holding = true;
  return F2S_OK;
  F2S_GUARD_END
}

f2s_status f2s_listener_counts(f2s_listener *listener, uint64_t *color, uint64_t *depth) {
  if (!listener || !color || !depth) return F2S_ERR_NULL_ARGUMENT;
  F2S_GUARD_BEGIN
  listener->listener.counts(color, depth);
  return F2S_OK;
  F2S_GUARD_END
}

f2s_status f2s_listener_frame(const f2s_listener *listener, f2s_frame_type type, f2s_frame_view *out) {
  if (!listener || !out) return F2S_ERR_NULL_ARGUMENT;
  F2S_GUARD_BEGIN
  if (!listener->holding) return F2S_ERR_NO_FRAME;
  libfreenect2::FrameMap::const_iterator it =
      listener->frames.find(static_cast<libfreenect2::Frame::Type>(type));
  if (it == listener->frames.end() || !it->second) return F2S_ERR_NO_FRAME;
  const libfreenect2::Frame *frame = it->second;
  out->width = frame->width;
  out->height = frame->height;
  out->bytes_per_pixel = frame->bytes_per_pixel;
  out->data = frame->data;
  out->timestamp = frame->timestamp;
  out->sequence = frame->sequence;
  out->exposure = frame->exposure;
  out->gain = frame->gain;
  out->gamma = frame->gamma;
  out->status = frame->status;
  out->format = static_cast<uint32_t>(frame->format);
  return F2S_OK;
  F2S_GUARD_END
}

f2s_status f2s_registration_new(const f2s_ir_params *ir, const f2s_color_params *color,
                                f2s_registration **out) {
  if (!ir || !color || !out) return F2S_ERR_NULL_ARGUMENT;
  *out = 0;
  F2S_GUARD_BEGIN
  *out = new f2s_registration(from_c(*ir), from_c(*color));
  return F2S_OK;
  F2S_GUARD_END
}

void f2s_registration_free(f2s_registration *registration) {
  try {
    delete registration;
  }
  F2S_VOID_CATCH
}

f2s_status f2s_registration_apply(f2s_registration *registration, const f2s_frame_view *color,
                                  const f2s_frame_view *depth, f2s_image *undistorted,
                                  f2s_image *registered, int32_t enable_filter) {
  if (!registration || !color || !depth || !undistorted || !registered)
    return F2S_ERR_NULL_ARGUMENT;
  if (!view_has_size(color, kColorWidth, kColorHeight, 4) ||
      !view_has_size(depth, kDepthWidth, kDepthHeight, 4) ||
      !image_has_size(undistorted, kDepthWidth, kDepthHeight, 4) ||
      !image_has_size(registered, kDepthWidth, kDepthHeight, 4))
    return F2S_ERR_BAD_SIZE;
  F2S_GUARD_BEGIN
  F2S_WRAP_VIEW(color_frame, color);
  F2S_WRAP_VIEW(depth_frame, depth);
  libfreenect2::Frame undistorted_frame(kDepthWidth, kDepthHeight, 4, undistorted->data);
  libfreenect2::Frame registered_frame(kDepthWidth, kDepthHeight, 4, registered->data);
  registration->registration.apply(&color_frame, &depth_frame, &undistorted_frame,
                                   &registered_frame, enable_filter != 0,
                                   &registration->big_depth, &registration->color_depth_map[0]);
  return F2S_OK;
  F2S_GUARD_END
}

f2s_status f2s_registration_undistort(const f2s_registration *registration,
                                      const f2s_frame_view *depth, f2s_image *undistorted) {
  if (!registration || !depth || !undistorted) return F2S_ERR_NULL_ARGUMENT;
  if (!view_has_size(depth, kDepthWidth, kDepthHeight, 4) ||
      !image_has_size(undistorted, kDepthWidth, kDepthHeight, 4))
    return F2S_ERR_BAD_SIZE;
  F2S_GUARD_BEGIN
  F2S_WRAP_VIEW(depth_frame, depth);
  libfreenect2::Frame undistorted_frame(kDepthWidth, kDepthHeight, 4, undistorted->data);
  registration->registration.undistortDepth(&depth_frame, &undistorted_frame);
  return F2S_OK;
  F2S_GUARD_END
}

}  // extern "C"

"""Makes and reads ROS bags with the `rosbags` package, for tests/tests/ros_bags.rs:
an implementation of the bag formats independent of ours.

    ros_bags.py write FORMAT FRAMES_JSON BAG   # FORMAT: ros1 | ros2-mcap | ros2-sqlite
    ros_bags.py read BAG OUT_DIR MSG_FILE      # prints JSON, writes OUT_DIR/depth-N.raw

FRAMES_JSON (written by the test): width, height, fx, fy, cx, cy, base_frame,
camera_frame, transform ([x, y, z], [qx, qy, qz, qw]) or null, depth_encoding
(16UC1 | 32FC1 | compressedDepth), stamps_ns, depth_raw (files of little-endian
uint16 millimetres) and depth_png (the recording's PNGs, for compressedDepth), and
color_raw (files of RGB bytes: a registered colour stream, color_encoding rgb8 or bgr8),
optional extras: no_camera_info (the topic without messages), zero_size (0 x 0
images).
"""

import json
import struct
import sys
from pathlib import Path

import numpy as np
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

TF_MSGS = {
    'tf2_msgs/msg/TFMessage': 'geometry_msgs/TransformStamped[] transforms\n',
}


def typestore_for(fmt):
    store = get_typestore(Stores.ROS1_NOETIC if fmt == 'ros1' else Stores.ROS2_HUMBLE)
    if 'tf2_msgs/msg/TFMessage' not in store.fielddefs:
        types = {}
        for name, text in TF_MSGS.items():
            types.update(get_types_from_msg(text, name))
        store.register(types)
    return store


def header(store, fmt, stamp_ns, frame_id):
    time = store.types['builtin_interfaces/msg/Time'](sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9)
    if fmt == 'ros1':
        return store.types['std_msgs/msg/Header'](seq=0, stamp=time, frame_id=frame_id)
    return store.types['std_msgs/msg/Header'](stamp=time, frame_id=frame_id)


def depth_message(store, fmt, spec, index, hdr):
    enc = spec['depth_encoding']
    width, height = (0, 0) if spec.get('zero_size') else (spec['width'], spec['height'])
    if enc == 'compressedDepth':
        # compressed_depth_image_transport: a ConfigHeader (int32 format, 1 = PNG;
        # float32 depthQuantA, depthQuantB) followed by the PNG of the 16-bit image.
        png = Path(spec['depth_png'][index]).read_bytes()
        data = struct.pack('<iff', 1, 0.0, 0.0) + png
        msg = store.types['sensor_msgs/msg/CompressedImage'](
            header=hdr, format='16UC1; compressedDepth png', data=np.frombuffer(data, dtype=np.uint8))
        return 'sensor_msgs/msg/CompressedImage', msg
    mm = np.fromfile(spec['depth_raw'][index], dtype='<u2')
    if enc == '32FC1':
        metres = np.where(mm == 0, np.nan, mm.astype(np.float32) / np.float32(1000.0)).astype('<f4')
        data, step = metres.view(np.uint8), width * 4
    else:
        data, step = mm.view(np.uint8), width * 2
    if spec.get('zero_size'):
        data = np.zeros(0, dtype=np.uint8)
    msg = store.types['sensor_msgs/msg/Image'](
        header=hdr, height=height, width=width, encoding=enc, is_bigendian=0, step=step, data=data)
    return 'sensor_msgs/msg/Image', msg


def color_message(store, spec, index, hdr):
    rgb = np.fromfile(spec['color_raw'][index], dtype=np.uint8)
    enc = spec.get('color_encoding', 'rgb8')
    if enc == 'bgr8':
        rgb = rgb.reshape(-1, 3)[:, ::-1].copy().reshape(-1)
    return store.types['sensor_msgs/msg/Image'](
        header=hdr, height=spec['height'], width=spec['width'], encoding=enc, is_bigendian=0,
        step=spec['width'] * 3, data=rgb)


def camera_info(store, fmt, spec, hdr):
    fx, fy, cx, cy = spec['fx'], spec['fy'], spec['cx'], spec['cy']
    k = np.array([fx, 0, cx, 0, fy, cy, 0, 0, 1], dtype=np.float64)
    r = np.eye(3).flatten()
    p = np.array([fx, 0, cx, 0, 0, fy, cy, 0, 0, 0, 1, 0], dtype=np.float64)
    roi = store.types['sensor_msgs/msg/RegionOfInterest'](
        x_offset=0, y_offset=0, height=0, width=0, do_rectify=False)
    names = ('D', 'K', 'R', 'P') if fmt == 'ros1' else ('d', 'k', 'r', 'p')
    fields = dict(zip(names, (np.zeros(5), k, r, p)))
    return store.types['sensor_msgs/msg/CameraInfo'](
        header=hdr, height=spec['height'], width=spec['width'], distortion_model='plumb_bob',
        binning_x=0, binning_y=0, roi=roi, **fields)


def tf_static(store, fmt, spec):
    (x, y, z), (qx, qy, qz, qw) = spec['transform']
    t = store.types
    transform = t['geometry_msgs/msg/TransformStamped'](
        header=header(store, fmt, spec['stamps_ns'][0], spec['base_frame']),
        child_frame_id=spec['camera_frame'],
        transform=t['geometry_msgs/msg/Transform'](
            translation=t['geometry_msgs/msg/Vector3'](x=x, y=y, z=z),
            rotation=t['geometry_msgs/msg/Quaternion'](x=qx, y=qy, z=qz, w=qw)))
    return t['tf2_msgs/msg/TFMessage'](transforms=[transform])


def write(fmt, spec_path, bag):
    spec = json.loads(Path(spec_path).read_text())
    store = typestore_for(fmt)
    ser = store.serialize_ros1 if fmt == 'ros1' else store.serialize_cdr
    if fmt == 'ros1':
        from rosbags.rosbag1 import Writer
        writer = Writer(bag)
    else:
        from rosbags.rosbag2 import StoragePlugin, Writer
        plugin = StoragePlugin.MCAP if fmt == 'ros2-mcap' else StoragePlugin.SQLITE3
        writer = Writer(bag, version=8, storage_plugin=plugin)
    conns = {}

    def put(topic, msgtype, msg, stamp):
        if topic not in conns:
            conns[topic] = writer.add_connection(topic, msgtype, typestore=store)
        writer.write(conns[topic], stamp, ser(msg, msgtype))

    depth_topic = '/kinect2/sd/image_depth_rect'
    if spec['depth_encoding'] == 'compressedDepth':
        depth_topic += '/compressed'
    with writer:
        if spec['transform'] is not None:
            put('/tf_static', 'tf2_msgs/msg/TFMessage', tf_static(store, fmt, spec), spec['stamps_ns'][0])
        for index, stamp in enumerate(spec['stamps_ns']):
            hdr = header(store, fmt, stamp, spec['camera_frame'])
            msgtype, msg = depth_message(store, fmt, spec, index, hdr)
            put(depth_topic, msgtype, msg, stamp)
            info_topic = '/kinect2/sd/camera_info'
            if spec.get('no_camera_info'):
                # The topic is there, its messages never come.
                if info_topic not in conns:
                    conns[info_topic] = writer.add_connection(
                        info_topic, 'sensor_msgs/msg/CameraInfo', typestore=store)
            else:
                put(info_topic, 'sensor_msgs/msg/CameraInfo', camera_info(store, fmt, spec, hdr), stamp)
            if spec.get('color_raw'):
                put('/kinect2/sd/image_color_rect', 'sensor_msgs/msg/Image',
                    color_message(store, spec, index, hdr), stamp)


def fields_of(text, name):
    return [[fname, repr(ftype)] for fname, ftype in get_types_from_msg(text, name)[name][1]]


def plain(value):
    """A deserialised message as JSON values (NaN as null)."""
    if hasattr(value, '__dataclass_fields__'):
        return {k: plain(getattr(value, k)) for k in value.__dataclass_fields__ if k != '__msgtype__'}
    if isinstance(value, np.ndarray):
        return plain(value.tolist())
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, float) and value != value:
        return None
    return value


def read(bag, out_dir, msg_file):
    out = {'topics': {}, 'depth': [], 'camera_info': [], 'estimates': [], 'tf_static': []}
    with AnyReader([Path(bag)]) as reader:
        for conn in reader.connections:
            out['topics'][conn.topic] = {'type': conn.msgtype, 'count': conn.msgcount,
                                         'encoding': getattr(conn.ext, 'serialization_format', None)}
            if conn.msgtype == 'slope_msgs/msg/SlopeEstimate':
                out['schema_fields'] = fields_of(conn.msgdef.data, conn.msgtype)
        for conn, stamp, raw in reader.messages():
            msg = reader.deserialize(raw, conn.msgtype)
            if conn.topic == '/slope/depth':
                n = len(out['depth'])
                Path(out_dir, f'depth-{n}.raw').write_bytes(bytes(msg.data))
                out['depth'].append({'log_time': stamp, 'width': msg.width, 'height': msg.height,
                                     'encoding': msg.encoding, 'step': msg.step,
                                     'stamp': [msg.header.stamp.sec, msg.header.stamp.nanosec],
                                     'frame_id': msg.header.frame_id})
            elif conn.topic == '/slope/camera_info':
                out['camera_info'].append({'k': plain(msg.k), 'width': msg.width, 'height': msg.height})
            elif conn.topic == '/slope/estimate':
                out['estimates'].append(plain(msg))
            elif conn.topic == '/tf_static':
                out['tf_static'].append(plain(msg))
    out['msg_file_fields'] = fields_of(Path(msg_file).read_text(), 'slope_msgs/msg/SlopeEstimate')
    print(json.dumps(out))


if __name__ == '__main__':
    if sys.argv[1] == 'write':
        write(*sys.argv[2:5])
    elif sys.argv[1] == 'read':
        read(*sys.argv[2:5])
    else:
        sys.exit(f'unknown command {sys.argv[1]}')

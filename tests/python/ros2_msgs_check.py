"""The .msg files of ros2/slope_msgs parsed by the `rosbags` message parser,
the standard messages from rosbags' ROS 2 Jazzy type store, and the IDL
types of ros2_types.py (what the Cyclone DDS test decodes with), as one
JSON object on stdout: {ROS type: {"idl": [[name, type]...], "msg": [...],
"humble": [...]}} (msg: Jazzy's store, humble: Humble's, each with our .msg
files) for every type of ros2_types.ALL, so that the test can check them
field for field.

usage: ros2_msgs_check.py MSG_DIR
"""

import json
import sys
from pathlib import Path

from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.base import Nodetype

import ros2_types


def type_text(desc) -> str:
    kind, detail = desc
    if kind == Nodetype.BASE:
        name, bound = detail
        return f"{name}<={bound}" if bound else name
    if kind == Nodetype.NAME:
        return detail
    if kind == Nodetype.ARRAY:
        inner, length = detail
        return f"{type_text(inner)}[{length}]"
    if kind == Nodetype.SEQUENCE:
        inner, bound = detail
        return f"{type_text(inner)}[<={bound}]" if bound else f"{type_text(inner)}[]"
    raise ValueError(f"unexpected field {desc!r}")


def main():
    msg_dir = Path(sys.argv[1])
    store = get_typestore(Stores.ROS2_JAZZY)
    ours = {}
    for path in sorted(msg_dir.glob("*.msg")):
        ours.update(get_types_from_msg(path.read_text(), f"slope_msgs/msg/{path.stem}"))
    store.register(ours)
    humble = get_typestore(Stores.ROS2_HUMBLE)
    humble.register(ours)
    out = {}
    for cls in ros2_types.ALL:
        name = ros2_types.ros_name(cls)
        _, fields = store.fielddefs[name]
        _, humble_fields = humble.fielddefs[name]
        out[name] = {
            "idl": ros2_types.fields(cls),
            "msg": [[field, type_text(desc)] for field, desc in fields],
            "humble": [[field, type_text(desc)] for field, desc in humble_fields],
            "ours": name in ours,
        }
    out["_msg_files"] = sorted(ours)
    print(json.dumps(out))


if __name__ == "__main__":
    main()

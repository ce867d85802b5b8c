"""Subscribes with Eclipse Cyclone DDS (PyPI `cyclonedds`) to the DDS topics
given and prints, one JSON line each on stdout:
  {"matched": TOPIC}                 once a writer of TOPIC has matched
  {"topic": TOPIC, "message": {...}} every sample (NaN as null)

usage: ros2_listen.py DOMAIN SECONDS TOPIC:TYPE:RELIABILITY:DURABILITY...
  e.g. rt/slope/estimate:SlopeEstimate:reliable:transient_local
       rt/slope/markers:MarkerArray:best_effort:volatile
TYPE is a class of ros2_types.py. Ends after SECONDS (a watchdog) or when
killed. Discovery and transport settings come from CYCLONEDDS_URI.
"""

import dataclasses
import json
import math
import sys
import time

from cyclonedds.core import InstanceState, Policy, Qos, ReadCondition, SampleState, ViewState, WaitSet
from cyclonedds.internal import InvalidSample
from cyclonedds.domain import DomainParticipant
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

import ros2_types


def plain(value):
    """A sample as JSON values: NaN and infinities as None."""
    if dataclasses.is_dataclass(value):
        return {f.name: plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, bytes):
        return list(value)
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def reader_qos(reliability: str, durability: str) -> Qos:
    policies = [Policy.History.KeepLast(1000)]
    if reliability == "reliable":
        policies.append(Policy.Reliability.Reliable(duration(seconds=1)))
    else:
        policies.append(Policy.Reliability.BestEffort)
    if durability == "transient_local":
        policies.append(Policy.Durability.TransientLocal)
    else:
        policies.append(Policy.Durability.Volatile)
    return Qos(*policies)


def emit(obj):
    print(json.dumps(obj), flush=True)


def main():
    domain = int(sys.argv[1])
    seconds = float(sys.argv[2])
    participant = DomainParticipant(domain)
    waitset = WaitSet(participant)
    readers = []
    for spec in sys.argv[3:]:
        name, type_name, reliability, durability = spec.split(":")
        cls = getattr(ros2_types, type_name)
        topic = Topic(participant, name, cls)
        reader = DataReader(participant, topic, qos=reader_qos(reliability, durability))
        condition = ReadCondition(
            reader, SampleState.Any | ViewState.Any | InstanceState.Any
        )
        waitset.attach(condition)
        readers.append([name, reader, False])
    until = time.monotonic() + seconds
    while time.monotonic() < until:
        waitset.wait(duration(milliseconds=50))
        for entry in readers:
            name, reader, matched = entry
            if not matched and reader.get_matched_publications():
                entry[2] = True
                emit({"matched": name})
            for sample in reader.take(N=100):
                if isinstance(sample, InvalidSample):
                    continue  # a writer left (no data)
                emit({"topic": name, "message": plain(sample)})


if __name__ == "__main__":
    main()

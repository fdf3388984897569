#!/usr/bin/env python3
"""Reads a trial's Foxglove channels the way Foxglove does, with the standard `mcap` reader and
`mcap-protobuf-support`'s DecoderFactory (which builds the messages from the FileDescriptorSet
in the file): every `foxglove.FrameTransforms` on /antenna/transforms and every
`foxglove.SceneUpdate` on /antenna/scene is decoded and checked against the poll recorded at
the same log time on /antenna/segments (JSON):

- link_{k+1}'s transform from link_k turns by segment k's recorded angle_rad (and is absent
  when the read failed), with link_k's length along x;
- link_0's transform from carriage turns by the rig's base mount angle plus the newest servo
  angle (/antenna/servo), when the metadata carries the rig;
- link_{k+1}'s four switch markers are red exactly where segment k's touch bits are set.

Works on a file left by kill -9 too (no summary). Usage: read_foxglove.py FILE.mcap

Prints one JSON object (transforms, scenes, links_checked, switches_checked, schemas) and exits
1 on the first mismatch, 2 on bad usage. Needs mcap and mcap-protobuf-support (scripts/setup
installs them).
"""

import json
import math
import sys

from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory

TOLERANCE = 1e-9


def fail(message):
    print(f"read_foxglove: FAIL: {message}", file=sys.stderr)
    sys.exit(1)


def angle_of(q):
    return 2.0 * math.atan2(q.z, q.w)


def same_angle(a, b):
    d = math.remainder(a - b, 2.0 * math.pi)
    return abs(d) < TOLERANCE


def main():
    if len(sys.argv) != 2:
        print("usage: read_foxglove.py FILE.mcap", file=sys.stderr)
        sys.exit(2)
    factory = DecoderFactory()
    decoders = {}
    polls = {}
    servo = []  # (log_time, base_angle_rad)
    transforms, scenes = [], []
    schemas = set()
    rig = None
    with open(sys.argv[1], "rb") as f:
        for schema, channel, message in make_reader(f).iter_messages():
            if channel.message_encoding == "json":
                data = json.loads(message.data)
                if channel.topic == "/antenna/segments":
                    polls[message.log_time] = data["segments"]
                elif channel.topic == "/antenna/servo":
                    servo.append((message.log_time, data["base_angle_rad"]))
                elif channel.topic == "/trial/metadata":
                    rig = data.get("rig")
                continue
            if channel.message_encoding != "protobuf":
                fail(f"{channel.topic}: message encoding {channel.message_encoding}")
            if channel.id not in decoders:
                decoder = factory.decoder_for(channel.message_encoding, schema)
                if decoder is None:
                    fail(f"{channel.topic}: no decoder for {schema.name}")
                decoders[channel.id] = decoder
                schemas.add(schema.name)
            decoded = decoders[channel.id](message.data)
            if channel.topic == "/antenna/transforms":
                transforms.append((message.log_time, decoded))
            elif channel.topic == "/antenna/scene":
                scenes.append((message.log_time, decoded))
    if not transforms or not scenes:
        fail(f"{len(transforms)} transforms and {len(scenes)} scenes")
    if schemas != {"foxglove.FrameTransforms", "foxglove.SceneUpdate"}:
        fail(f"schemas {schemas}")

    links_checked = 0
    for log_time, message in transforms:
        poll = polls.get(log_time)
        if poll is None:
            fail(f"transforms at {log_time} ns: no poll at that log time")
        by_child = {t.child_frame_id: t for t in message.transforms}
        for t in message.transforms:
            if (t.timestamp.seconds * 10**9 + t.timestamp.nanos) != log_time:
                fail(f"{t.child_frame_id} at {log_time} ns: timestamp {t.timestamp}")
        for k, sample in enumerate(poll):
            child = f"link_{k + 1}"
            t = by_child.get(child)
            if sample["angle_rad"] is None:
                if t is not None:
                    fail(f"{child} at {log_time} ns: a transform for a failed read")
                continue
            if t is None:
                fail(f"{child} at {log_time} ns: no transform")
            if t.parent_frame_id != f"link_{k}":
                fail(f"{child}: parent {t.parent_frame_id}")
            if not same_angle(angle_of(t.rotation), sample["angle_rad"]):
                fail(f"{child} at {log_time} ns: {angle_of(t.rotation)} rad, "
                     f"recorded {sample['angle_rad']}")
            if rig is not None and abs(t.translation.x - rig["link_lengths_m"][k]) > TOLERANCE:
                fail(f"{child}: translation {t.translation.x}")
            if abs(t.translation.y) > TOLERANCE:
                fail(f"{child}: translation y {t.translation.y}")
            links_checked += 1
        if rig is not None:
            # The newest servo angle before the poll, or one at the poll's own time (recorded
            # before or after it): 0 before the first.
            mount = math.radians(rig["base_mount_angle_deg"])
            before = [a for (lt, a) in servo if lt < log_time]
            at = [a for (lt, a) in servo if lt == log_time]
            wants = [mount + (before[-1] if before else 0.0)] + [mount + a for a in at]
            t = by_child.get("link_0")
            if t is None or t.parent_frame_id != "carriage":
                fail(f"link_0 at {log_time} ns: {t}")
            if not any(same_angle(angle_of(t.rotation), w) for w in wants):
                fail(f"link_0 at {log_time} ns: {angle_of(t.rotation)} rad, want one of {wants}")

    switches_checked = 0
    for log_time, message in scenes:
        poll = polls.get(log_time)
        if poll is None:
            fail(f"scene at {log_time} ns: no poll at that log time")
        entities = {e.id: e for e in message.entities}
        for k, sample in enumerate(poll):
            entity = entities.get(f"link_{k + 1}")
            if entity is None or entity.frame_id != f"link_{k + 1}":
                fail(f"scene at {log_time} ns: link_{k + 1}: {entity}")
            if len(entity.spheres) != 4:
                fail(f"link_{k + 1}: {len(entity.spheres)} switches")
            for j, sphere in enumerate(entity.spheres):
                red = sphere.color.r > 0.8 and sphere.color.g < 0.2
                bits = sample["touch"]
                if bits is not None and red != bool(bits >> j & 1):
                    fail(f"scene at {log_time} ns: link_{k + 1} switch {j}: red={red}, "
                         f"touch bits {bits:#06b}")
                switches_checked += 1

    print(json.dumps({
        "transforms": len(transforms),
        "scenes": len(scenes),
        "links_checked": links_checked,
        "switches_checked": switches_checked,
        "schemas": sorted(schemas),
    }))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Reads a trial file the way a scientist would, with nothing but the standard `mcap` reader:
`make_reader(f).iter_messages()`, no recovery code. Used on a file left by `kill -9`.

Usage: read_killed.py FILE.mcap

Prints one JSON object: polls (the /antenna/segments messages read), first_seq and last_seq,
last_t_s, started_unix_ns (from /trial/metadata) and log_times_ok (every poll's log time is
started_unix_ns + t_s in nanoseconds). Exits non-zero if the reader raises.
"""

import json
import sys

from mcap.reader import make_reader


def main():
    if len(sys.argv) != 2:
        print("usage: read_killed.py FILE.mcap", file=sys.stderr)
        sys.exit(2)
    polls, metadata = [], None
    with open(sys.argv[1], "rb") as f:
        for _schema, channel, message in make_reader(f).iter_messages():
            # The Foxglove channels (/antenna/transforms, /antenna/scene) are protobuf.
            if channel.message_encoding != "json":
                continue
            data = json.loads(message.data)
            if channel.topic == "/antenna/segments":
                polls.append((message.log_time, data["t_s"], data.get("seq")))
            elif channel.topic == "/trial/metadata":
                metadata = data
    started = metadata["started_unix_ns"] if metadata else None
    print(json.dumps({
        "polls": len(polls),
        "first_seq": polls[0][2] if polls else None,
        "last_seq": polls[-1][2] if polls else None,
        "last_t_s": polls[-1][1] if polls else None,
        "started_unix_ns": started,
        "log_times_ok": started is not None
        and all(log_time == started + round(t_s * 1e9) for log_time, t_s, _ in polls),
    }))


if __name__ == "__main__":
    main()

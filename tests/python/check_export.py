#!/usr/bin/env python3
"""Checks a trial recorded by antennad and exported by `antenna export` with the tools a
scientist would use: the Python `mcap` reader on the MCAP file (complete and cut short by a
crash), `scipy.io.loadmat` on the MAT-file, and the `csv` module on the CSV file.

Usage: check_export.py EXPECTED.json

EXPECTED.json (written by crates/antenna-cli/tests/export_python.rs) names the files and holds
the values that were recorded: t_s, seq, address, angle_rad, angle_counts and touch (polls x
segments, null for a missing sample), the flags ok, nack, pec_error, bus_error and stale (polls
x segments), stage_t_s, stage_position_m, servo_t_s, base_angle_rad, estimate (the wall estimates' messages as
recorded), trial, config, notes,
started_unix_ns, truncated_mcap and truncated_polls; `whole` (a second trial whose doubles are
all whole numbers, its base angle all zero) and `empty_mat` (a trial with no polls). The MAT-files
are read with scipy's default `loadmat(path)`, no options, and every variable's dtype is checked.
Exits non-zero with a message on the first mismatch. Needs scipy and mcap (scripts/setup
installs them).
"""

import csv
import json
import math
import sys

import numpy as np
import scipy.io
from mcap.reader import make_reader

TOPICS = {"/trial/metadata", "/antenna/segments", "/antenna/stage", "/antenna/servo",
          "/antenna/estimate"}


def fail(message):
    print(f"check_export: FAIL: {message}", file=sys.stderr)
    sys.exit(1)


def check(condition, message):
    if not condition:
        fail(message)


def same(a, b):
    """Equal values, None and NaN standing for a missing sample."""
    if a is None or (isinstance(a, float) and math.isnan(a)):
        return b is None or (isinstance(b, float) and math.isnan(b))
    return b is not None and float(a) == float(b)


def check_mcap(e):
    polls, stage, servo, estimate, metadata = [], [], [], [], None
    with open(e["mcap"], "rb") as f:
        reader = make_reader(f, validate_crcs=True)
        summary = reader.get_summary()
        check(summary is not None, "the complete trial has a summary")
        for schema in summary.schemas.values():
            check(schema.encoding == "jsonschema", f"schema encoding {schema.encoding}")
            json.loads(schema.data)
        topics = {c.topic for c in summary.channels.values()}
        check(topics == TOPICS, f"topics {topics}")
        for channel in summary.channels.values():
            check(channel.message_encoding == "json", f"{channel.topic}: encoding")
        for _schema, channel, message in reader.iter_messages():
            data = json.loads(message.data)
            if channel.topic == "/antenna/segments":
                check(message.log_time == e["started_unix_ns"] + round(data["t_s"] * 1e9),
                      "log time is the Unix-epoch start plus t_s, in ns")
                polls.append(data)
            elif channel.topic == "/antenna/stage":
                stage.append(data)
            elif channel.topic == "/antenna/servo":
                servo.append(data)
            elif channel.topic == "/antenna/estimate":
                estimate.append(data)
            else:
                metadata = data
        records = list(reader.iter_metadata())
        check([r.name for r in records] == ["trial"], "one Metadata record named trial")
        check(records[0].metadata["trial"] == e["trial"], "Metadata record: trial")
    check(len(polls) == len(e["t_s"]), f"MCAP: {len(polls)} polls, expected {len(e['t_s'])}")
    for i, poll in enumerate(polls):
        check(poll["t_s"] == e["t_s"][i], f"MCAP: t_s of poll {i}")
        check(poll["seq"] == e["seq"][i], f"MCAP: seq of poll {i}")
        for k, seg in enumerate(poll["segments"]):
            check(seg["address"] == e["address"][k], f"MCAP: address {i},{k}")
            check(same(seg["angle_rad"], e["angle_rad"][i][k]), f"MCAP: angle_rad {i},{k}")
            check(same(seg["touch"], e["touch"][i][k]), f"MCAP: touch {i},{k}")
    check([s["t_s"] for s in stage] == e["stage_t_s"], "MCAP: stage times")
    check([s["position_m"] for s in stage] == e["stage_position_m"], "MCAP: stage positions")
    check([s["t_s"] for s in servo] == e["servo_t_s"], "MCAP: servo times")
    check([s["base_angle_rad"] for s in servo] == e["base_angle_rad"], "MCAP: base angles")
    check(estimate == e["estimate"], "MCAP: estimates")
    check(metadata is not None and metadata["trial"] == e["trial"], "MCAP: metadata message")
    check(metadata["notes"] == e["notes"], "MCAP: notes")
    print(f"check_export: MCAP ok ({len(polls)} polls, {len(stage)} stage, {len(servo)} servo)")


def check_truncated_mcap(e):
    """A file left by kill -9 (never closed) opens in the standard reader as it is, with
    every flushed poll: no recovery code, no exception."""
    polls = []
    with open(e["truncated_mcap"], "rb") as f:
        reader = make_reader(f, validate_crcs=True)
        check(reader.get_summary() is None, "an unclosed file has no summary")
        for _schema, channel, message in reader.iter_messages():
            if channel.topic == "/antenna/segments":
                polls.append(json.loads(message.data))
    check(len(polls) == e["truncated_polls"],
          f"truncated MCAP: {len(polls)} polls, {e['truncated_polls']} were flushed")
    for i, poll in enumerate(polls):
        check(poll["t_s"] == e["t_s"][i], f"truncated MCAP: t_s of poll {i}")
        for k, seg in enumerate(poll["segments"]):
            check(same(seg["angle_rad"], e["angle_rad"][i][k]), f"truncated: angle {i},{k}")
    print(f"check_export: truncated MCAP ok ({len(polls)} polls)")


# The class each MAT-file variable loads as with scipy's default loadmat (no options): doubles
# stay float64 even when every value is whole (the writer never stores them as integer types);
# counters, addresses, raw counts and touch bits are integers; logical flags load as uint8.
MAT_DTYPES = {
    "t_s": np.float64, "seq": np.uint64, "address": np.uint8, "angle_rad": np.float64,
    "angle_counts": np.uint16, "touch": np.uint8, "ok": np.uint8, "nack": np.uint8,
    "pec_error": np.uint8, "bus_error": np.uint8, "stale": np.uint8,
    "stage_t_s": np.float64, "stage_position_m": np.float64, "servo_t_s": np.float64,
    "base_angle_rad": np.float64, "started_unix_s": np.float64, "started_unix_ns": np.uint64,
    "estimate_t_s": np.float64, "estimate_seq": np.uint64, "estimate_distance_m": np.float64,
    "estimate_angle_rad": np.float64, "estimate_preview_m": np.float64,
    "estimate_true_distance_m": np.float64, "estimate_true_angle_rad": np.float64,
}
# Cell arrays of char (object arrays in scipy), E x 1.
MAT_TEXT_CELLS = ["estimator", "estimate_reason"]
# The estimates' doubles and the message fields they come from (null: NaN).
ESTIMATE_DOUBLES = {
    "estimate_t_s": "t_s", "estimate_distance_m": "distance_m", "estimate_angle_rad": "angle_rad",
    "estimate_preview_m": "preview_m", "estimate_true_distance_m": "true_distance_m",
    "estimate_true_angle_rad": "true_angle_rad",
}


def check_dtypes(m, label):
    for name, dtype in MAT_DTYPES.items():
        check(name in m, f"{label}: no variable {name}")
        check(m[name].dtype == dtype, f"{label}: {name} is {m[name].dtype}, not {dtype.__name__}")
    for name in MAT_TEXT_CELLS:
        check(name in m, f"{label}: no variable {name}")
        check(m[name].dtype == object, f"{label}: {name} is {m[name].dtype}, not a cell array")


def text(char_array):
    """The text of a loaded char array ('' is stored 0 x 0 and loads empty)."""
    return str(char_array[0]) if char_array.size else ""


def check_estimates_mat(m, estimates, label):
    n = len(estimates)
    for name in list(ESTIMATE_DOUBLES) + ["estimate_seq"] + MAT_TEXT_CELLS:
        check(m[name].shape == (n, 1), f"{label}: {name} has shape {m[name].shape}, not {(n, 1)}")
    for name, field in ESTIMATE_DOUBLES.items():
        for i, x in enumerate(estimates):
            check(same(x.get(field), m[name][i, 0]), f"{label}: {name}[{i}]")
    check(np.array_equal(m["estimate_seq"][:, 0], np.array([x["seq"] for x in estimates],
                                                           dtype=np.uint64)), f"{label}: seq")
    for i, x in enumerate(estimates):
        check(text(m["estimator"][i, 0]) == x["estimator"], f"{label}: estimator[{i}]")
        check(text(m["estimate_reason"][i, 0]) == x.get("reason", ""), f"{label}: reason[{i}]")


def check_mat(e):
    m = scipy.io.loadmat(e["mat"])
    check_dtypes(m, "MAT")
    n, s = len(e["t_s"]), len(e["address"])
    expected_shapes = {
        "t_s": (n, 1), "seq": (n, 1), "address": (1, s), "angle_rad": (n, s), "angle_counts": (n, s),
        "touch": (n, s), "ok": (n, s), "nack": (n, s), "pec_error": (n, s),
        "bus_error": (n, s), "stale": (n, s),
        "stage_t_s": (len(e["stage_t_s"]), 1), "stage_position_m": (len(e["stage_t_s"]), 1),
        "servo_t_s": (len(e["servo_t_s"]), 1), "base_angle_rad": (len(e["servo_t_s"]), 1),
        "started_unix_s": (1, 1), "started_unix_ns": (1, 1),
    }
    for name, shape in expected_shapes.items():
        check(m[name].shape == shape, f"MAT: {name} has shape {m[name].shape}, expected {shape}")
    check(np.array_equal(m["t_s"][:, 0], np.array(e["t_s"])), "MAT: t_s")
    check(np.array_equal(m["seq"][:, 0], np.array(e["seq"], dtype=np.uint64)), "MAT: seq")
    check(np.array_equal(m["address"][0], np.array(e["address"])), "MAT: address")
    angle = np.array([[np.nan if v is None else v for v in row] for row in e["angle_rad"]])
    check(np.array_equal(m["angle_rad"], angle, equal_nan=True), "MAT: angle_rad")
    # Integers have no NaN: a missing sample is 0 there, and ok says which are missing.
    counts = np.array([[0 if v is None else v for v in row] for row in e["angle_counts"]])
    check(np.array_equal(m["angle_counts"], counts), "MAT: angle_counts")
    touch = np.array([[0 if v is None else v for v in row] for row in e["touch"]])
    check(np.array_equal(m["touch"], touch), "MAT: touch")
    for flag in ["ok", "nack", "pec_error", "bus_error", "stale"]:
        check(np.array_equal(m[flag], np.array(e[flag], dtype=np.uint8)), f"MAT: {flag}")
    check(np.array_equal(np.isnan(m["angle_rad"]), m["ok"] == 0), "MAT: ok flags")
    check(np.array_equal(m["stage_t_s"][:, 0], np.array(e["stage_t_s"])), "MAT: stage_t_s")
    check(np.array_equal(m["stage_position_m"][:, 0], np.array(e["stage_position_m"])),
          "MAT: stage_position_m")
    check(np.array_equal(m["servo_t_s"][:, 0], np.array(e["servo_t_s"])), "MAT: servo_t_s")
    check(np.array_equal(m["base_angle_rad"][:, 0], np.array(e["base_angle_rad"])),
          "MAT: base_angle_rad")
    check(m["started_unix_ns"][0, 0] == e["started_unix_ns"], "MAT: started_unix_ns")
    check(str(m["trial"][0]) == e["trial"], f"MAT: trial {m['trial']!r}")
    check(str(m["config"][0]) == e["config"], f"MAT: config {m['config']!r}")
    check(m["truncated"].size == 0, f"MAT: truncated {m['truncated']!r}")
    notes = {str(m["notes"][i, 0][0]): str(m["notes"][i, 1][0]) for i in range(m["notes"].shape[0])}
    check(notes == e["notes"], f"MAT: notes {notes}")
    check_estimates_mat(m, e["estimate"], "MAT")
    print(f"check_export: MAT ok ({n} x {s}, {len(e['estimate'])} estimates)")


def check_mat_whole_numbers(e):
    """A trial whose doubles are all whole (base angle all zero, stage at whole metres, whole
    seconds): they load as float64 all the same, so arithmetic on them does not wrap."""
    w = e["whole"]
    m = scipy.io.loadmat(w["mat"])
    check_dtypes(m, "MAT of whole numbers")
    zeros = m["base_angle_rad"]
    check(zeros.shape == (w["servo"], 1) and np.all(zeros == 0.0), f"whole: base angle {zeros!r}")
    check(np.all(zeros - 1 == -1.0), "whole: base_angle_rad - 1 is -1, not 255")
    check(np.array_equal(m["stage_position_m"][:, 0], np.array(w["stage_position_m"])),
          "whole: stage_position_m")
    check(np.array_equal(m["t_s"][:, 0], np.array(w["t_s"])), "whole: t_s")
    check(np.all(m["t_s"][:1] - 1 == -1.0), "whole: t_s - 1")
    print(f"check_export: MAT of whole numbers ok ({w['servo']} zero base angles)")


def check_mat_empty(e):
    """A trial with no polls: empty arrays, each of its class."""
    m = scipy.io.loadmat(e["empty_mat"])
    check_dtypes(m, "empty MAT")
    for name in ["t_s", "seq", "stage_t_s", "stage_position_m", "servo_t_s", "base_angle_rad"]:
        check(m[name].shape == (0, 1), f"empty MAT: {name} has shape {m[name].shape}")
    for name in ["angle_rad", "angle_counts", "touch", "ok"]:
        check(m[name].size == 0, f"empty MAT: {name} has shape {m[name].shape}")
    check_estimates_mat(m, [], "empty MAT")
    print("check_export: empty MAT ok")


def check_csv(e):
    with open(e["csv"], newline="") as f:
        lines = [line for line in f if not line.startswith("#")]
    rows = list(csv.DictReader(lines))
    n, s = len(e["t_s"]), len(e["address"])
    check(len(rows) == n * s, f"CSV: {len(rows)} rows, expected {n * s}")
    estimates, latest = e["estimate"], -1
    for j, row in enumerate(rows):
        i, k = j // s, j % s
        # The estimate columns: the latest estimate at or before the poll (empty before it).
        while latest + 1 < len(estimates) and estimates[latest + 1]["t_s"] <= e["t_s"][i]:
            latest += 1
        x = estimates[latest] if latest >= 0 else {}
        check(row["estimate_seq"] == ("" if latest < 0 else str(x["seq"])), f"CSV row {j}: estimate_seq")
        check(row["estimator"] == x.get("estimator", ""), f"CSV row {j}: estimator")
        check(row["estimate_reason"] == x.get("reason", ""), f"CSV row {j}: estimate_reason")
        for name, field in ESTIMATE_DOUBLES.items():
            if name != "estimate_t_s":
                value = None if row[name] == "" else float(row[name])
                check(same(value, x.get(field)), f"CSV row {j}: {name}")
        check(int(row["poll"]) == i, f"CSV row {j}: poll")
        check(int(row["seq"]) == e["seq"][i], f"CSV row {j}: seq")
        check(float(row["t_s"]) == e["t_s"][i], f"CSV row {j}: t_s")
        check(int(row["address"]) == e["address"][k], f"CSV row {j}: address")
        a = None if row["angle_rad"] == "" else float(row["angle_rad"])
        check(same(a, e["angle_rad"][i][k]), f"CSV row {j}: angle_rad")
        t = None if row["touch"] == "" else int(row["touch"])
        check(same(t, e["touch"][i][k]), f"CSV row {j}: touch")
    print(f"check_export: CSV ok ({len(rows)} rows)")


def main():
    if len(sys.argv) != 2:
        fail("usage: check_export.py EXPECTED.json")
    with open(sys.argv[1]) as f:
        e = json.load(f)
    check_mcap(e)
    check_truncated_mcap(e)
    check_mat(e)
    check_mat_whole_numbers(e)
    check_mat_empty(e)
    check_csv(e)
    print("check_export: all ok")


if __name__ == "__main__":
    main()

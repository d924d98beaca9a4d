#!/usr/bin/env python3
"""Reads an MCAP file with the `mcap` package from PyPI (an independent
reader) and prints, as JSON: per topic its schema name and encoding, its
message encoding and its message count; the summary's statistics; and the
messages whose log_time is not their record's `t` in nanoseconds, or that
are not JSON objects of their channel's kinds.

    python3 read.py FILE.mcap
"""

import json
import sys

from mcap.reader import make_reader


def main(path):
    out = {"topics": {}, "bad": [], "message_count": None}
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        if summary is not None and summary.statistics is not None:
            out["message_count"] = summary.statistics.message_count
        for channel in (summary.channels.values() if summary else []):
            schema = summary.schemas.get(channel.schema_id)
            out["topics"][channel.topic] = {
                "schema": schema.name if schema else None,
                "schema_encoding": schema.encoding if schema else None,
                "schema_is_json": _is_json(schema.data) if schema else False,
                "message_encoding": channel.message_encoding,
                "count": 0,
            }
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            t = out["topics"][channel.topic]
            t["count"] += 1
            try:
                record = json.loads(message.data)
            except ValueError as e:
                out["bad"].append("%s: not JSON: %s" % (channel.topic, e))
                continue
            if round(record["t"] * 1e9) != message.log_time:
                out["bad"].append("%s: log_time %d for t %r" % (channel.topic, message.log_time, record["t"]))
            t.setdefault("kinds", {})
            t["kinds"][record["kind"]] = t["kinds"].get(record["kind"], 0) + 1
    print(json.dumps(out, sort_keys=True))


def _is_json(data):
    try:
        return isinstance(json.loads(data), dict)
    except ValueError:
        return False


if __name__ == "__main__":
    main(sys.argv[1])

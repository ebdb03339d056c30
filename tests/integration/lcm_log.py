#!/usr/bin/env python3
"""Reads an LCM log (lcm-logger) for the integration tests, without the lcm Python module.

Usage:
  lcm_log.py maps LOG        one line per SLAM_MAP message:
                             recv_utime map_id version is_snapshot acked_below max_acked
                             (max_acked = acked_below - 1: the newest acknowledged id)
  lcm_log.py status LOG CH   one line per status_t message on channel CH:
                             recv_utime component state name=value ... (counters only)
  lcm_log.py keyframes LOG   one line per SLAM_KEYFRAME message: recv_utime map_id keyframe_id

Decodes the leading fields of rgbdslam's map_t, status_t and keyframe_t (lcmtypes/) by
hand: LCM encodes big-endian after an 8-byte fingerprint, strings as an int32 length
(including the terminating NUL) and the bytes. A message that does not decode is skipped
and counted on stderr.
"""
import struct
import sys

SYNC = 0xEDA1DA01


def events(path):
    with open(path, "rb") as f:
        data = f.read()
    pos = 0
    while pos + 28 <= len(data):
        sync, _eventnum, utime, chan_len, data_len = struct.unpack_from(">IqqII", data, pos)
        if sync != SYNC:
            raise SystemExit(f"{path}: bad sync word at byte {pos}")
        pos += 28
        channel = data[pos:pos + chan_len].decode("utf-8", "replace")
        pos += chan_len
        payload = data[pos:pos + data_len]
        pos += data_len
        if len(payload) == data_len:
            yield utime, channel, payload


class Reader:
    def __init__(self, payload):
        self.b, self.p = payload, 8  # after the fingerprint

    def take(self, fmt):
        v = struct.unpack_from(">" + fmt, self.b, self.p)
        self.p += struct.calcsize(">" + fmt)
        return v[0] if len(v) == 1 else v

    def string(self):
        n = self.take("i")
        s = self.b[self.p:self.p + n - 1].decode("utf-8", "replace")
        self.p += n
        return s


def main():
    if len(sys.argv) < 3:
        raise SystemExit(__doc__)
    what, path = sys.argv[1], sys.argv[2]
    bad = 0
    for utime, channel, payload in events(path):
        try:
            r = Reader(payload)
            if what == "maps" and channel == "SLAM_MAP":
                _t, map_id, version, snap, acked_below = r.take("qqqbq")
                print(utime, map_id, version, int(snap != 0), acked_below, acked_below - 1)
            elif what == "keyframes" and channel == "SLAM_KEYFRAME":
                _t, map_id, kf = r.take("qqq")
                print(utime, map_id, kf)
            elif what == "status" and channel == sys.argv[3]:
                r.take("q")
                component, state = r.string(), r.string()
                n = r.take("i")
                names = [r.string() for _ in range(n)]
                values = [r.take("q") for _ in range(n)]
                print(utime, component, state.replace(" ", "_"),
                      " ".join(f"{k}={v}" for k, v in zip(names, values)))
        except (struct.error, UnicodeDecodeError):
            bad += 1
    if bad:
        print(f"lcm_log.py: {bad} messages did not decode", file=sys.stderr)


if __name__ == "__main__":
    main()

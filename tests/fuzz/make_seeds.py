#!/usr/bin/env python3
"""Write the seed corpora of the stateful harnesses (tests/fuzz/corpus/).

Run with the project venv (cantools): .venv/bin/python tests/fuzz/make_seeds.py
The seeds speak the harnesses' operation encodings (tests/fuzz/README.md):
  app_rx    a fault-free start: sensor and setpoint frames encoded with the
            DBC (plausible values), 1 ms steps; and a sensor dropout;
  uds       a workshop session: each service once, SecurityAccess with the
            right and a wrong key, a segmented request, S3 and the delay;
  nvm       a torn store, a bit flip, a real-image raw payload start;
  scenario  the smallest SIL scenarios (copied by the Makefile's author,
            not here).
"""
import os
import struct

import cantools

HERE = os.path.dirname(os.path.abspath(__file__))
db = cantools.database.load_file(os.path.join(HERE, "..", "..", "dbc", "canfdi.dbc"))


def write(harness, name, data):
    d = os.path.join(HERE, "corpus", harness)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(bytes(data))


def frame(msg, **sig):
    m = db.get_message_by_name(msg)
    full = {s.name: 0 for s in m.signals}
    full.update(sig)
    return m.encode(full, strict=False)


# app_rx: op 0 + b (index in bits 0..1, counter +1) + bytes 1..7; op 4 + step byte
def app_rx_cycle(ua, ia, om, tps, speed, angle):
    out = []
    for k, f in enumerate([frame("DcmSensor", DcmUa=ua, DcmIa=ia, DcmOmega=om, DcmUsupply=24.0),
                           frame("ThrSensor", ThrTps1=tps, ThrTps2=5.0 - tps, ThrImot=0.5, ThrUsupply=12.0),
                           frame("SetpointDcm", SpDcmSpeed=speed, SpDcmLoad=0.1),
                           frame("SetpointThr", SpThrAngle=angle)]):
        out += [0, k] + list(f[1:8])
    out += [4, 0x80]  # one step, no jitter
    return out


seed = []
for i in range(60):
    seed += app_rx_cycle(12.0, 1.0, 100.0 * min(1.0, i / 30), 1.0, 100.0, 10.0)
write("app_rx", "nominal_start", seed)
seed = []
for i in range(30):
    seed += app_rx_cycle(12.0, 1.0, 50.0, 1.0, 50.0, 10.0)
seed += [4, 0x8F] * 4  # 64 ms without frames: the inputs time out
for i in range(10):
    seed += app_rx_cycle(12.0, 1.0, 50.0, 1.0, 50.0, 10.0)
write("app_rx", "dropout", seed)
write("app_rx", "raw_frames", [3, 0x00, 0x10, 5, 1, 2, 3, 4, 5, 3, 0x01, 0x23, 8] + list(range(8)) + [4, 0x83])


# uds: op 3 = a whole request (len-1, bytes); op 5 = steps; op 6 = key
def req(*b):
    return [3, len(b) - 1] + list(b)


def wait(n):
    return [5, n - 1]


s = []
s += req(0x10, 0x03) + wait(5)
s += req(0x27, 0x01) + wait(5) + [6, 0x00] + wait(5)  # seed, right key
s += req(0x22, 0xF1, 0x90) + wait(10)
s += req(0x22, 0xF1, 0x90, 0xF1, 0x8C, 0xF1, 0x95, 0x02, 0x00) + wait(30)  # segmented
s += req(0x19, 0x01, 0xFF) + wait(5) + req(0x19, 0x02, 0xFF) + wait(20)
s += req(0x19, 0x0A) + wait(40) + req(0x19, 0x06, 0xFF, 0xFF, 0xFF, 0xFF) + wait(10)
s += req(0x31, 0x01, 0x02, 0x01) + wait(10) + req(0x31, 0x03, 0x02, 0x01) + wait(5)
s += req(0x2F, 0x03, 0x00, 0x03, 0x00, 0x00) + wait(5)
s += req(0x28, 0x01, 0x01) + wait(5) + req(0x3E, 0x00) + wait(5) + req(0x3E, 0x80) + wait(5)
s += [7, 3, 1, 8, 7, 3, 1] + req(0x14, 0xFF, 0xFF, 0xFF) + wait(5)
s += req(0x11, 0x01) + wait(5)
write("uds", "session", s)
s = []
s += req(0x10, 0x03) + wait(5)
for _ in range(4):
    s += req(0x27, 0x01) + wait(5) + [6, 0x02 | (5 << 2)] + wait(5)  # wrong keys
s += [5, 0xF9] + req(0x10, 0x03) + wait(5) + req(0x27, 0x01) + wait(5) + [6, 0x00] + wait(5)  # after the delay
write("uds", "security_delay", s)
write("uds", "functional", [2, 8, 0x02, 0x3E, 0x00, 0, 0, 0, 0, 0, 5, 3, 2, 8, 0x02, 0x10, 0x01, 0, 0, 0, 0, 0, 5, 3])
write("uds", "s3_timeout", req(0x10, 0x03) + wait(5) + [5, 0xF5] + req(0x22, 0xF1, 0x90) + wait(5))

# nvm: mode byte, then the modes' fields
write("nvm", "torn_mid_image", [1, 3, 1, 1, 1, 1, 0xF0] + [5, 2, 1, 3, 1, 0xF0, 4, 1, 1] + [0x01, 0x20])
write("nvm", "torn_in_erase", [1, 2, 1, 1, 0xF0] + [0] + [0x00, 0x10])
write("nvm", "bit_flip", [2, 2, 1, 1, 0xF0] + [3, 1, 1, 2, 1, 0xF0, 1] + [0, 0x00, 0x00, 0x11, 0x23])
write("nvm", "empty_device", [0])
write("nvm", "raw_header_only", [3, 0x02, 0x00, 0x00, 0x00])

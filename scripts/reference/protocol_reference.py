#!/usr/bin/env python3
"""Reference vectors for the feed-override protocol's framing, from implementations cutlab did not
write: CRC-32 from Python's zlib (the zlib C library's crc32) and COBS from the PyPI package `cobs`
(cobs.cobs.encode).

Writes tests/reference/protocol/framing.json, which tests/protocol.rs loads with include_str!
(natively and under wasm). Regenerate with

    pip install cobs==1.2.2        # any version with cobs.cobs.encode
    python3 scripts/reference/protocol_reference.py

What is computed:
  crc32   zlib.crc32 of the catalogue's check string "123456789", the empty string, a pangram,
          every length 0-64 of one byte pattern, and seeded random byte strings up to 600 bytes.
  cobs    cobs.cobs.encode of the examples in the Wikipedia article on COBS (after Cheshire and
          Baker's paper), of runs with and without zeros at the lengths around its 254-byte group,
          and of seeded random blocks (with zeros) up to 300 bytes.
  frames  for one random payload of every frame type's layout, the bytes on the wire:
          0x00, COBS(payload + CRC-32(payload) little-endian), 0x00 (docs/protocol.md section 2),
          composed here from zlib and `cobs` alone.

All byte strings are stored as lowercase hex.
"""

import json
import os
import platform
import random
import zlib
from importlib.metadata import version

from cobs import cobs

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "..", "..", "tests", "reference", "protocol")

# Frame type codes and payload lengths (type byte included), docs/protocol.md section 3.
LAYOUTS = {
    "hello": (0x01, 3),
    "capabilities": (0x02, 114),
    "sample": (0x10, 44),
    "sim-truth": (0x11, 69),
    "set-override": (0x20, 12),
    "arm": (0x21, 5),
    "disarm": (0x22, 5),
    "reset": (0x23, 5),
    "ack": (0x30, 10),
    "fault": (0x31, 14),
    "heartbeat": (0x40, 15),
}


def crc_case(data):
    return {"data": data.hex(), "crc32": zlib.crc32(data)}


def cobs_case(data):
    return {"data": data.hex(), "encoded": cobs.encode(data).hex()}


def wikipedia_examples():
    """The examples of https://en.wikipedia.org/wiki/Consistent_Overhead_Byte_Stuffing."""
    run = bytes(range(1, 256))  # 01 02 ... ff
    return [
        bytes([0x00]),
        bytes([0x00, 0x00]),
        bytes([0x00, 0x11, 0x00]),
        bytes([0x11, 0x22, 0x00, 0x33]),
        bytes([0x11, 0x22, 0x33, 0x44]),
        bytes([0x11, 0x00, 0x00, 0x00]),
        run[:254],  # 01 ... fe
        bytes([0x00]) + run[:254],  # 00 01 ... fe
        run,  # 01 ... ff
        run[1:] + bytes([0x00]),  # 02 ... ff 00
        run[2:] + bytes([0x00, 0x01]),  # 03 ... ff 00 01
    ]


def main():
    rng = random.Random(16)
    crc = [crc_case(b"123456789"), crc_case(b""),
           crc_case(b"The quick brown fox jumps over the lazy dog")]
    pattern = bytes((i * 37 + 11) % 256 for i in range(64))
    crc += [crc_case(pattern[:n]) for n in range(65)]
    crc += [crc_case(rng.randbytes(rng.randrange(1, 600))) for _ in range(40)]

    blocks = wikipedia_examples()
    for n in (0, 1, 2, 253, 254, 255, 256, 507, 508, 509, 510):
        blocks.append(bytes((i % 255) + 1 for i in range(n)))  # no zero
        blocks.append(bytes(n))  # all zeros
    for _ in range(60):
        n = rng.randrange(0, 300)
        # About one byte in eight a zero, so groups of every length occur.
        blocks.append(bytes(0 if rng.random() < 0.125 else rng.randrange(1, 256)
                            for _ in range(n)))
    cobs_cases = [cobs_case(b) for b in blocks]

    frames = []
    for name, (code, length) in LAYOUTS.items():
        for _ in range(3):
            payload = bytes([code]) + rng.randbytes(length - 1)
            body = payload + zlib.crc32(payload).to_bytes(4, "little")
            wire = b"\x00" + cobs.encode(body) + b"\x00"
            frames.append({"type": name, "payload": payload.hex(), "wire": wire.hex()})

    doc = {
        "generator": {
            "script": "scripts/reference/protocol_reference.py",
            "python": platform.python_version(),
            "zlib": zlib.ZLIB_VERSION,
            "cobs": version("cobs"),
        },
        "crc32": crc,
        "cobs": cobs_cases,
        "frames": frames,
    }
    os.makedirs(OUT, exist_ok=True)
    with open(os.path.join(OUT, "framing.json"), "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()

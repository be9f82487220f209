# SPDX-License-Identifier: GPL-3.0-or-later
"""Deterministic fuzzing of msii's input: mutates the seed files (tests/fuzz/seeds/), runs
`msii compute` on each mutant and checks what msii promises for every input:

- status 0: the output exists, every stderr line is a printable `msii: ...` line, and no
  temporary file is left;
- status 1: stderr is exactly one printable line `msii: error: ...`, and the folder holds
  nothing but the input (no output, no temporary file);
- never a signal, never status 2 (wrong usage: the command line is always right), never more
  than TIME_LIMIT seconds, never more than MEMORY_LIMIT bytes of address space, and never
  more than PEAK_MEMORY_LIMIT resident (msii refuses cleanly at the address-space limit, so
  that limit alone would let a few-KB input that takes gigabytes pass).

Mutant k of a format is made by random.Random("SEED/FORMAT/k") alone, so `--seed S` gives the
same mutants on every machine and any failure can be made again with `--only K`.

    /usr/bin/python3 tests/fuzz/fuzz.py --msii build/tools/msii --count 300 --seed 1 --keep fuzz-failures
"""
import argparse
import math
import os
import random
import re
import resource
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time
import unicodedata

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from make_seeds import COMPANIONS, SEED_DIR, SEEDS, seed_format  # noqa: E402

FORMATS = ("ply", "off", "obj", "stl", "tif", "asc")
RASTER_FORMATS = ("tif", "asc")
TIME_LIMIT = 30.0           # seconds of wall time per run
MEMORY_LIMIT = 4 << 30      # bytes of address space per run
FILE_SIZE_LIMIT = 1 << 30   # bytes per file written: a runaway output is a failure, not a full disk
# Peak resident memory per run. The seeds take 0.1 to 0.3 GB; a mutant of a few KB that takes
# more than this was sized by a number in the file rather than by its contents. Under the
# address-space limit msii fails cleanly ("out of memory"), which alone would hide that.
PEAK_MEMORY_LIMIT = 2 << 30

# Replacements for numbers, as text and as binary fields: the values that break readers and
# geometry (signs, zero, overflow, NaN, float32's lowest value and -9999 as undeclared
# nodata, 2^32 for 32-bit counters).
TEXT_NUMBERS = ["-1", "0", "1", "1e308", "-1e308", "nan", "inf", "-inf", "4294967296", "-3.4028235e38",
                "-9999", "1e400", "1e-320", "2147483648", "-0"]
FLOAT_NUMBERS = [-1.0, 0.0, 1.0, 1e308, math.nan, math.inf, -math.inf, 2.0 ** 32, -3.4028235e38, -9999.0,
                 1e-40, 1e30]
INT_NUMBERS = [-1, 0, 1, 2, 255, 65535, 2 ** 31 - 1, 2 ** 31, 2 ** 32 - 1, 2 ** 32, -2 ** 31]
COUNTS = ["0", "1", "-1", "2147483647", "2147483648", "4294967295", "4294967296", "18446744073709551616",
          "1000000000", "1e9", "x"]

NUMBER = re.compile(rb"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


class Mutant:
    """A seed's bytes being mutated, with its companion files and the notes that say how."""

    def __init__(self, seed, name, data, companions):
        self.seed = seed
        self.name = name
        self.data = bytearray(data)
        self.companions = {k: bytearray(v) for k, v in companions.items()}
        self.notes = []

    def note(self, text):
        self.notes.append(text)

    @property
    def format(self):
        return seed_format(self.seed)


def line_of(data, offset):
    return data.count(b"\n", 0, offset) + 1


def shown(data):
    """Bytes of a mutant for a note: as they are, bytes that are not UTF-8 escaped."""
    return bytes(data).decode("utf-8", "backslashreplace")


def pick(rng, values):
    return values[rng.randrange(len(values))]


# ---------------------------------------------------------------------------------------
# Mutations for every format: bytes flipped, cut, inserted, repeated, removed.

def flip_bytes(rng, m):
    if not m.data:
        return False
    offsets = sorted(rng.randrange(len(m.data)) for _ in range(rng.randint(1, 8)))
    for offset in offsets:
        m.data[offset] ^= (1 << rng.randrange(8)) if rng.random() < 0.6 else rng.randrange(1, 256)
    m.note("flipped bytes at %s" % ",".join(map(str, offsets)))
    return True


def truncate(rng, m):
    if len(m.data) < 2:
        return False
    at = rng.randrange(len(m.data))
    del m.data[at:]
    m.note("truncated at byte %d" % at)
    return True


def insert_random(rng, m):
    at = rng.randrange(len(m.data) + 1)
    count = rng.choice([1, 2, 4, 8, 64, 512])
    m.data[at:at] = bytes(rng.randrange(256) for _ in range(count))
    m.note("inserted %d random bytes at byte %d" % (count, at))
    return True


def duplicate_run(rng, m):
    if not m.data:
        return False
    start = rng.randrange(len(m.data))
    length = min(rng.choice([1, 4, 16, 50, 100, 1000]), len(m.data) - start)
    at = rng.randrange(len(m.data) + 1)
    times = rng.choice([1, 1, 2, 10])
    m.data[at:at] = bytes(m.data[start:start + length]) * times
    m.note("copied bytes %d..%d %d time(s) to byte %d" % (start, start + length, times, at))
    return True


def delete_run(rng, m):
    if len(m.data) < 2:
        return False
    start = rng.randrange(len(m.data))
    length = rng.choice([1, 2, 4, 12, 50, 300])
    del m.data[start:start + length]
    m.note("deleted %d bytes at byte %d" % (length, start))
    return True


GENERIC = [(12, flip_bytes), (8, truncate), (6, insert_random), (7, duplicate_run), (4, delete_run)]


# ---------------------------------------------------------------------------------------
# Text formats: numbers replaced, lines removed or repeated.

def replace_numbers(rng, m, start=0):
    """Replaces 1 to 3 numbers after byte @p start by special values."""
    numbers = list(NUMBER.finditer(m.data, start))
    if not numbers:
        return False
    chosen = sorted(rng.sample(numbers, min(len(numbers), rng.choice([1, 1, 1, 2, 3]))),
                    key=lambda match: match.start(), reverse=True)
    notes = []
    for match in chosen:
        value = pick(rng, TEXT_NUMBERS)
        notes.append("line %d: %s -> %s" % (line_of(m.data, match.start()), shown(match.group()), value))
        m.data[match.start():match.end()] = value.encode()
    m.note("numbers replaced: " + "; ".join(reversed(notes)))
    return True


def edit_lines(rng, m, start=0):
    """Removes, repeats or swaps whole lines after byte @p start."""
    head, body = bytes(m.data[:start]), bytes(m.data[start:])
    lines = body.split(b"\n")
    if len(lines) < 2:
        return False
    i = rng.randrange(len(lines))
    first = line_of(m.data, start)
    what = rng.choice(["removed", "repeated", "swapped"])
    if what == "removed":
        del lines[i]
    elif what == "repeated":
        lines[i:i] = [lines[i]] * rng.choice([1, 5])
    else:
        j = rng.randrange(len(lines))
        lines[i], lines[j] = lines[j], lines[i]
        what = "swapped with line %d:" % (first + j)
    m.data = bytearray(head + b"\n".join(lines))
    m.note("line %d %s" % (first + i, what))
    return True


def replace_word(rng, m, old, choices):
    """Replaces one occurrence of the line-leading word @p old by one of @p choices."""
    hits = [match.start(1) for match in re.finditer(rb"(?m)^\s*(" + re.escape(old) + rb")\b", m.data)]
    if not hits:
        return False
    at = pick(rng, hits)
    new = pick(rng, choices)
    m.data[at:at + len(old)] = new
    m.note("line %d: %r -> %r" % (line_of(m.data, at), shown(old), new.decode("latin-1")))
    return True


# ---------------------------------------------------------------------------------------
# PLY

PLY_TYPES = {"char": "b", "int8": "b", "uchar": "B", "uint8": "B", "short": "h", "int16": "h",
             "ushort": "H", "uint16": "H", "int": "i", "int32": "i", "uint": "I", "uint32": "I",
             "float": "f", "float32": "f", "double": "d", "float64": "d"}


def ply_layout(data):
    """(format, elements [(name, count, [(property, type, item type or None)])], body offset),
    or None where the header cannot be read."""
    end = data.find(b"end_header")
    newline = data.find(b"\n", end)
    if not data.startswith(b"ply") or end < 0 or newline < 0:
        return None
    fmt, elements = None, []
    for line in bytes(data[:newline]).decode("latin-1").splitlines():
        words = line.split()
        if len(words) >= 2 and words[0] == "format":
            fmt = words[1]
        elif len(words) >= 3 and words[0] == "element":
            elements.append((words[1], int(words[2]) if words[2].isdigit() else 0, []))
        elif words[:2] == ["property", "list"] and len(words) >= 5 and elements:
            elements[-1][2].append((words[4], words[2], words[3]))
        elif len(words) >= 3 and words[0] == "property" and elements:
            elements[-1][2].append((words[2], words[1], None))
    return fmt, elements, newline + 1


def ply_binary_fields(data, layout, limit=100000):
    """(offset, struct code, description) of the numbers of a binary PLY's body, in order."""
    fmt, elements, pos = layout
    endian = "<" if fmt == "binary_little_endian" else ">"
    fields = []
    for name, count, properties in elements:
        for record in range(count):
            for prop, kind, item in properties:
                code = PLY_TYPES.get(kind)
                if code is None or pos + struct.calcsize(code) > len(data) or len(fields) > limit:
                    return fields
                if item is None:
                    fields.append((pos, code, "%s %d %s (%s)" % (name, record, prop, kind)))
                    pos += struct.calcsize(code)
                    continue
                fields.append((pos, code, "%s %d %s count (%s)" % (name, record, prop, kind)))
                items = struct.unpack_from(endian + code, data, pos)[0]
                items = int(items) if math.isfinite(items) else 0  # a count typed float by a mutation
                pos += struct.calcsize(code)
                item_code = PLY_TYPES.get(item)
                if item_code is None:
                    return fields
                for k in range(max(0, min(items, 1000))):
                    if pos + struct.calcsize(item_code) > len(data):
                        return fields
                    fields.append((pos, item_code, "%s %d %s[%d] (%s)" % (name, record, prop, k, item)))
                    pos += struct.calcsize(item_code)
    return fields


def pack_number(endian, code, rng):
    """A special value packed as @p code; returns (bytes, text of the value)."""
    if code in "fd":
        value = pick(rng, FLOAT_NUMBERS)
        if code == "f" and math.isfinite(value) and abs(value) > 3.4028234663852886e38:
            return struct.pack(endian + "f", math.copysign(math.inf, value)), "%r (as float32: inf)" % value
        return struct.pack(endian + code, value), repr(value)
    value = pick(rng, INT_NUMBERS)
    bits = 8 * struct.calcsize(code)
    return struct.pack(endian + code.upper(), value & ((1 << bits) - 1)), str(value)


def write_binary_field(rng, m, fields, endian):
    offset, code, what = pick(rng, fields)
    if rng.random() < 0.2:  # a field of another width at the same place: halves of doubles and the like
        code = rng.choice("fdi")
        what = "bytes at %d as %s" % (offset, {"f": "float32", "d": "float64", "i": "int32"}[code])
    packed, text = pack_number(endian, code, rng)
    m.data[offset:offset + len(packed)] = packed[:max(0, len(m.data) - offset)]
    m.note("%s -> %s" % (what, text))
    return True


def ply_numbers(rng, m):
    layout = ply_layout(m.data)
    if layout is None:
        return False
    if layout[0] == "ascii":
        return replace_numbers(rng, m, layout[2])
    fields = ply_binary_fields(m.data, layout)
    return bool(fields) and write_binary_field(rng, m, fields, "<" if layout[0] == "binary_little_endian" else ">")


def ply_lines(rng, m):
    layout = ply_layout(m.data)
    return layout is not None and layout[0] == "ascii" and edit_lines(rng, m, layout[2])


def ply_header(rng, m):
    layout = ply_layout(m.data)
    if layout is None:
        return False
    header = bytes(m.data[:layout[2]]).decode("latin-1").split("\n")
    body = bytes(m.data[layout[2]:])
    lines = [i for i, line in enumerate(header) if line.strip()]
    what = rng.choice(["count", "count", "count", "type", "list", "format", "remove", "repeat", "insert", "magic"])
    if what == "count":
        targets = [i for i in lines if header[i].startswith("element ")]
        if not targets:
            return False
        i = pick(rng, targets)
        words = header[i].split()
        old = int(words[2]) if words[2].isdigit() else 0
        words[2] = pick(rng, COUNTS + [str(old + 1), str(old - 1), str(old + 1), str(old - 1)])
        header[i] = " ".join(words)
    elif what == "type":
        targets = [i for i in lines if header[i].startswith("property ") and " list " not in header[i]]
        if not targets:
            return False
        i = pick(rng, targets)
        words = header[i].split()
        words[1] = pick(rng, list(PLY_TYPES) + ["bogus", "list"])
        header[i] = " ".join(words)
    elif what == "list":
        targets = [i for i in lines if header[i].startswith("property list ")]
        if not targets:
            return False
        i = pick(rng, targets)
        words = header[i].split()
        words[2 + rng.randrange(2)] = pick(rng, list(PLY_TYPES) + ["bogus"])
        header[i] = " ".join(words)
    elif what == "format":
        i = next((i for i in lines if header[i].startswith("format ")), None)
        if i is None:
            return False
        header[i] = pick(rng, ["format ascii 1.0", "format binary_little_endian 1.0", "format binary_big_endian 1.0",
                               "format ascii 2.0", "format xyz 1.0", "format"])
    elif what in ("remove", "repeat"):
        i = pick(rng, lines[1:] or lines)
        header[i:i + 1] = [] if what == "remove" else [header[i]] * 2
    elif what == "insert":
        i = rng.randrange(1, len(header))
        header[i:i] = [pick(rng, ["element vertex 3", "property float x", "property double z", "element face 0",
                                  "property list uchar int vertex_indices", "comment \x01\x02\x1b[31m",
                                  "obj_info " + "x" * 5000, "property float", "element", "element vertex",
                                  "property list uchar", "element vertex 99999999999999999999999"])]
    else:
        i = 0
        header[0] = pick(rng, ["PLY", "ply extra", "pl", "ply\r", ""])
    m.data = bytearray("\n".join(header).encode("latin-1") + body)
    m.note("header line %d %s: %r" % (i + 1, what, header[i] if i < len(header) else ""))
    return True


# ---------------------------------------------------------------------------------------
# OFF

def off_body(data):
    """Offset just after the counts line (the first line of numbers after the keyword)."""
    pos = 0
    for line in bytes(data).split(b"\n"):
        pos += len(line) + 1
        words = line.split(b"#")[0].split()
        if len(words) == 3 and all(w.lstrip(b"-").isdigit() for w in words):
            return pos
    return None


def off_numbers(rng, m):
    start = off_body(m.data)
    return start is not None and replace_numbers(rng, m, start)


def off_header(rng, m):
    start = off_body(m.data)
    what = rng.choice(["count", "count", "count", "keyword", "lines"])
    if what == "lines" or start is None:
        return edit_lines(rng, m)
    if what == "keyword":
        return replace_word(rng, m, b"OFF", [b"COFF", b"NOFF", b"4OFF", b"OFF BINARY", b"OF", b"STOFF", b"off", b""])
    head = bytes(m.data[:start]).split(b"\n")
    counts = head[-2].split()
    k = rng.randrange(3)
    old = int(counts[k])
    counts[k] = pick(rng, COUNTS + [str(old + 1), str(old - 1)] * 2).encode()
    head[-2] = b" ".join(counts)
    m.data[:start] = b"\n".join(head)
    m.note("counts line %d: %s" % (len(head) - 1, shown(head[-2])))
    return True


# ---------------------------------------------------------------------------------------
# OBJ

def obj_numbers(rng, m):
    return replace_numbers(rng, m)


def obj_structure(rng, m):
    """Face references out of range or malformed, faces of 1, 2 or many corners, vertices with
    too few or too many numbers, lines removed or repeated."""
    vertices = len(re.findall(rb"(?m)^v ", m.data))
    faces = list(re.finditer(rb"(?m)^f ([^\n]*)$", m.data))
    what = rng.choice(["index", "index", "index", "corners", "vertex", "lines", "keyword"])
    if what == "lines":
        return edit_lines(rng, m)
    if what == "keyword":
        return replace_word(rng, m, pick(rng, [b"v", b"vn", b"vt", b"f"]),
                            [b"V", b"vv", b"vp", b"l", b"p", b"g", b"s", b"usemtl", b"mtllib", b"#"])
    if what == "vertex":
        lines = list(re.finditer(rb"(?m)^v ([^\n]*)$", m.data))
        if not lines:
            return False
        line = pick(rng, lines)
        words = line.group(1).split()
        words = words[:rng.randrange(len(words))] if rng.random() < 0.5 else words + [b"1"] * rng.choice([1, 3, 10])
        m.data[line.start(1):line.end(1)] = b" ".join(words)
        m.note("line %d: v %s" % (line_of(m.data, line.start()), shown(b" ".join(words))))
        return True
    if not faces:
        return False
    face = pick(rng, faces)
    refs = face.group(1).split()
    if what == "index" and refs:
        k = rng.randrange(len(refs))
        parts = refs[k].split(b"/")
        part = rng.randrange(len(parts))
        parts[part] = pick(rng, ["0", "-1", str(vertices + 1), str(-vertices - 1), "2147483648", "4294967297",
                                 "99999999999999999999", "nan", "1.5", "", "-0", "x"]).encode()
        refs[k] = b"/".join(parts) if rng.random() < 0.9 else refs[k] + b"/1/2"
    else:
        count = rng.choice([0, 1, 2, 4, 300])
        refs = (refs * 100)[:count]
    m.data[face.start(1):face.end(1)] = b" ".join(refs)
    m.note("line %d: f %s" % (line_of(m.data, face.start()), shown(b" ".join(refs))[:200]))
    return True


# ---------------------------------------------------------------------------------------
# STL

def is_binary_stl(m):
    return not m.seed.endswith("_ascii.stl")


def stl_numbers(rng, m):
    if not is_binary_stl(m):
        return replace_numbers(rng, m)
    records = (len(m.data) - 84) // 50
    if records <= 0:
        return False
    fields = [(84 + 50 * r + 4 * k, "f", "triangle %d %s" % (r, "normal" if k < 3 else "corner %d" % ((k - 3) // 3)))
              for r in range(records) for k in range(12)]
    fields += [(84 + 50 * r + 48, "H", "triangle %d attribute" % r) for r in range(records)]
    return write_binary_field(rng, m, fields, "<")


def stl_header(rng, m):
    if not is_binary_stl(m):
        what = rng.choice(["keyword", "keyword", "lines", "vertex"])
        if what == "lines":
            return edit_lines(rng, m)
        if what == "vertex":
            return replace_word(rng, m, b"vertex", [b"vertex 1 2 3\n vertex", b"vertex 1", b"vertex\n"])
        old = pick(rng, [b"solid", b"facet", b"outer", b"vertex", b"endloop", b"endfacet", b"endsolid"])
        return replace_word(rng, m, old, [b"", b"x", b"solid", b"facet", b"endsolid", b"endfacet", b"vertex"])
    if len(m.data) < 84:
        return False
    what = rng.choice(["count", "count", "count", "solid"])
    if what == "solid":  # a binary STL whose header starts like an ASCII one, as some exporters write
        m.data[0:6] = b"solid "
        m.note("header starts with 'solid '")
        return True
    old = struct.unpack_from("<I", m.data, 80)[0]
    new = pick(rng, [0, 1, old - 1, old + 1, old * 2, 2 ** 31, 2 ** 32 - 1, 85899345])
    struct.pack_into("<I", m.data, 80, new & 0xFFFFFFFF)
    m.note("triangle count %d -> %d" % (old, new & 0xFFFFFFFF))
    return True


# ---------------------------------------------------------------------------------------
# GeoTIFF: the pixel data and the tags of every image file directory.

TIFF_TYPES = {1: 1, 2: 1, 3: 2, 4: 4, 5: 8, 6: 1, 7: 1, 8: 2, 9: 4, 10: 8, 11: 4, 12: 8, 16: 8, 17: 8, 18: 8}
TIFF_CODES = {1: "B", 3: "H", 4: "I", 6: "b", 8: "h", 9: "i", 11: "f", 12: "d", 16: "Q", 17: "q", 18: "Q"}
TIFF_TAGS = {256: "ImageWidth", 257: "ImageLength", 258: "BitsPerSample", 259: "Compression",
             262: "Photometric", 270: "ImageDescription", 273: "StripOffsets", 277: "SamplesPerPixel",
             278: "RowsPerStrip", 279: "StripByteCounts", 284: "PlanarConfig", 317: "Predictor",
             322: "TileWidth", 323: "TileLength", 324: "TileOffsets", 325: "TileByteCounts",
             339: "SampleFormat", 33550: "ModelPixelScale", 33922: "ModelTiepoint",
             34264: "ModelTransformation", 34735: "GeoKeyDirectory", 34736: "GeoDoubleParams",
             34737: "GeoAsciiParams", 42112: "GDAL_METADATA", 42113: "GDAL_NODATA"}


def tiff_entries(data):
    """(endian, [(entry offset, tag, type, count, value offset)]) of a classic TIFF, or None."""
    if len(data) < 8 or data[:2] not in (b"II", b"MM"):
        return None
    endian = "<" if data[:2] == b"II" else ">"
    if struct.unpack_from(endian + "H", data, 2)[0] != 42:
        return None
    entries, seen = [], set()
    ifd = struct.unpack_from(endian + "I", data, 4)[0]
    while 0 < ifd and ifd + 2 <= len(data) and ifd not in seen and len(seen) < 16:
        seen.add(ifd)
        n = struct.unpack_from(endian + "H", data, ifd)[0]
        for i in range(n):
            pos = ifd + 2 + 12 * i
            if pos + 12 > len(data):
                break
            tag, kind, count = struct.unpack_from(endian + "HHI", data, pos)
            size = TIFF_TYPES.get(kind, 1) * count
            value = pos + 8 if size <= 4 else struct.unpack_from(endian + "I", data, pos + 8)[0]
            entries.append((pos, tag, kind, count, value))
        next_at = ifd + 2 + 12 * n
        ifd = struct.unpack_from(endian + "I", data, next_at)[0] if next_at + 4 <= len(data) else 0
    return endian, entries


def tiff_values(data, endian, entry):
    _, _, kind, count, value = entry
    code = TIFF_CODES.get(kind)
    if code not in ("H", "I", "Q") or value + count * TIFF_TYPES[kind] > len(data):
        return []
    return list(struct.unpack_from(endian + code * count, data, value))


def tiff_pixel_data(data, endian, entries):
    """[(offset, bytes)] of every strip or tile."""
    by_tag = {}
    for entry in entries:
        by_tag.setdefault(entry[1], entry)
    segments = []
    for offsets_tag, counts_tag in ((273, 279), (324, 325)):
        if offsets_tag in by_tag and counts_tag in by_tag:
            offsets = tiff_values(data, endian, by_tag[offsets_tag])
            counts = tiff_values(data, endian, by_tag[counts_tag])
            segments += [(o, c) for o, c in zip(offsets, counts) if c > 0 and o + c <= len(data)]
    return segments


def tif_numbers(rng, m):
    parsed = tiff_entries(m.data)
    if parsed is None:
        return False
    endian, entries = parsed
    segments = tiff_pixel_data(m.data, endian, entries)
    if not segments:
        return False
    start, size = pick(rng, segments)
    cells = []
    for _ in range(rng.choice([1, 1, 3, 100])):
        cell = rng.randrange(max(1, size // 4))
        cells.append((start + 4 * cell, "f", "pixel data, float32 %d of the strip at %d" % (cell, start)))
    packed, text = pack_number(endian, "f", rng)
    for offset, _, _ in cells:
        m.data[offset:offset + 4] = packed
    m.note("%s%s -> %s" % (cells[0][2], " and %d more" % (len(cells) - 1) if len(cells) > 1 else "", text))
    return True


def tif_tags(rng, m):
    parsed = tiff_entries(m.data)
    if parsed is None:
        return False
    endian, entries = parsed
    if not entries:
        return False
    interesting = [e for e in entries if e[1] in TIFF_TAGS]
    entry = pick(rng, interesting if interesting and rng.random() < 0.85 else entries)
    pos, tag, kind, count, value = entry
    name = "tag %d %s" % (tag, TIFF_TAGS.get(tag, ""))
    what = rng.choice(["value", "value", "value", "value", "count", "type", "id", "ifd"])
    if what == "value":
        size = TIFF_TYPES.get(kind, 1)
        k = rng.randrange(count) if count else 0
        at = value + k * size
        if count == 0 or at + size > len(m.data):
            return False
        if kind == 2:  # ASCII: a number in the text, as GDAL_NODATA holds
            text = pick(rng, TEXT_NUMBERS + ["", "-3.4028234663852886e+38", "abc"]).encode() + b"\0"
            text = text[:count - k]
            m.data[at:at + len(text)] = text
            m.note("%s text at %d -> %r" % (name, k, text))
            return True
        code = TIFF_CODES.get(kind)
        if code is None:
            m.data[at] ^= 0xFF
            m.note("%s value %d: byte inverted" % (name, k))
            return True
        packed, text = pack_number(endian, code, rng)
        m.data[at:at + len(packed)] = packed
        m.note("%s value %d -> %s" % (name, k, text))
        return True
    if what == "count":
        new = pick(rng, [0, 1, count - 1, count + 1, count * 2, 2 ** 31, 2 ** 32 - 1]) & 0xFFFFFFFF
        struct.pack_into(endian + "I", m.data, pos + 4, new)
        m.note("%s count %d -> %d" % (name, count, new))
        return True
    if what == "type":
        new = rng.randrange(0, 20)
        struct.pack_into(endian + "H", m.data, pos + 2, new)
        m.note("%s type %d -> %d" % (name, kind, new))
        return True
    if what == "id":
        new = pick(rng, [0, 65535, tag + 1, tag - 1] + list(TIFF_TAGS)) & 0xFFFF
        struct.pack_into(endian + "H", m.data, pos, new)
        m.note("%s renamed to tag %d" % (name, new))
        return True
    new = pick(rng, [0, 1, 8, len(m.data), len(m.data) - 2, 2 ** 32 - 1])
    struct.pack_into(endian + "I", m.data, 4, new)
    m.note("first directory offset -> %d" % new)
    return True


# ---------------------------------------------------------------------------------------
# ESRI ASCII grid, and its .prj

ASC_KEYS = (b"ncols", b"nrows", b"xllcorner", b"yllcorner", b"xllcenter", b"yllcenter", b"cellsize",
            b"dx", b"dy", b"nodata_value")
GEOGRAPHIC_WKT = ('GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563]],'
                  'PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433]]')


def asc_body(data):
    pos = 0
    for line in bytes(data).split(b"\n"):
        words = line.split()
        if not words or words[0].lower() not in ASC_KEYS:
            return pos
        pos += len(line) + 1
    return pos


def asc_numbers(rng, m):
    return replace_numbers(rng, m, asc_body(m.data))


def asc_header(rng, m):
    what = rng.choice(["value", "value", "value", "value", "lines", "key", "prj"])
    if what == "prj":
        prj = next(iter(m.companions))
        new = pick(rng, [GEOGRAPHIC_WKT, "", "PROJCS[", "EPSG:4326", "garbage\x01", "LOCAL_CS[\"none\"]"])
        m.companions[prj] = bytearray(new.encode())
        m.note("%s replaced by %r" % (prj, new))
        return True
    end = asc_body(m.data)
    if what == "lines":
        head = bytes(m.data[:end]).split(b"\n")
        i = rng.randrange(max(1, len(head) - 1))
        head[i:i + 1] = [] if rng.random() < 0.5 else [head[i]] * 2
        m.data[:end] = b"\n".join(head)
        m.note("header line %d %s" % (i + 1, "removed or repeated"))
        return True
    lines = list(re.finditer(rb"(?m)^(\S+)([ \t]+)(\S+)", bytes(m.data[:end])))
    if not lines:
        return False
    line = pick(rng, lines)
    key = line.group(1).lower()
    if what == "key":
        new_key = pick(rng, list(ASC_KEYS) + [b"xllcorne", b"NCOLS", b"cellsize cellsize"])
        m.data[line.start(1):line.end(1)] = new_key
        m.note("header %s -> %s" % (shown(key), shown(new_key)))
        return True
    old = int(line.group(3)) if line.group(3).isdigit() else 0
    if key in (b"ncols", b"nrows"):
        new = pick(rng, COUNTS + [str(old + 1), str(old - 1)] * 2)
    else:
        new = pick(rng, TEXT_NUMBERS + ["1e-300", "0.5"])
    m.data[line.start(3):line.end(3)] = new.encode()
    m.note("header %s %s -> %s" % (shown(key), shown(line.group(3)), new))
    return True


# Per format: the mutations besides the generic ones, with weights.
MUTATIONS = {
    "ply": [(25, ply_numbers), (22, ply_header), (4, ply_lines)],
    "off": [(25, off_numbers), (20, off_header)],
    "obj": [(25, obj_numbers), (25, obj_structure)],
    "stl": [(25, stl_numbers), (20, stl_header)],
    "tif": [(25, tif_numbers), (30, tif_tags)],
    "asc": [(25, asc_numbers), (22, asc_header)],
}


def make_mutant(fmt, k, seed):
    """Mutant @p k of format @p fmt: the same bytes for the same (seed, fmt, k), always."""
    seeds = [name for name in SEEDS if seed_format(name) == fmt]
    source = seeds[k % len(seeds)]
    rng = random.Random("%d/%s/%d" % (seed, fmt, k))
    stem, ext = source.rsplit(".", 1)
    name = "%s-%04d.%s" % (stem, k, ext)
    companions = {}
    for companion in COMPANIONS.get(source, []):
        with open(os.path.join(SEED_DIR, companion), "rb") as f:
            companions["%s-%04d.%s" % (companion.rsplit(".", 1)[0], k, companion.rsplit(".", 1)[1])] = f.read()
    with open(os.path.join(SEED_DIR, source), "rb") as f:
        mutant = Mutant(source, name, f.read(), companions)
    choices = GENERIC + MUTATIONS[fmt]
    total = sum(weight for weight, _ in choices)
    for _ in range(rng.choice([1, 1, 1, 1, 1, 1, 2, 2, 2, 3])):
        for _attempt in range(20):
            x = rng.uniform(0, total)
            for weight, mutation in choices:
                x -= weight
                if x <= 0:
                    break
            if mutation(rng, mutant):
                break
    return mutant


# ---------------------------------------------------------------------------------------
# Running msii and judging what it did.

def limit_resources():
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))
    resource.setrlimit(resource.RLIMIT_FSIZE, (FILE_SIZE_LIMIT, FILE_SIZE_LIMIT))
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))


def command(msii, input_name, radius, raster, output=None):
    output = output or ("out.tif" if raster else "out.ply")
    return [msii, "compute", input_name, "-r", str(radius), "-n", "4", "--overwrite",
            "--raster-output" if raster else "-o", output]


class Process:
    """A program run in @p folder under the limits, its stderr kept in an unnamed file (the
    folder holds only what the program writes), its peak memory measured."""

    def __init__(self, command, folder):
        self.start = time.monotonic()
        self.stderr_file = tempfile.TemporaryFile()
        self.popen = subprocess.Popen(command, cwd=folder, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                      stderr=self.stderr_file, preexec_fn=limit_resources)
        self.status = None        # exit status, or -signal
        self.peak_bytes = 0       # peak resident memory
        self.timed_out = False
        self.seconds = 0.0

    def poll(self, block=False):
        """True once the program has ended (killed at TIME_LIMIT)."""
        if self.status is not None:
            return True
        pid, wait_status, usage = os.wait4(self.popen.pid, 0 if block else os.WNOHANG)
        if pid == 0 and time.monotonic() - self.start > TIME_LIMIT:
            self.timed_out = True
            self.popen.kill()
            pid, wait_status, usage = os.wait4(self.popen.pid, 0)
        if pid == 0:
            return False
        self.popen.returncode = self.status = os.waitstatus_to_exitcode(wait_status)
        self.peak_bytes = usage.ru_maxrss * 1024
        self.seconds = time.monotonic() - self.start
        return True

    def wait(self):
        while not self.poll():
            time.sleep(0.01)
        return self

    def stderr(self):
        self.stderr_file.seek(0)
        data = self.stderr_file.read()
        self.stderr_file.close()
        return data


def judge(status, stderr_bytes, folder, inputs, output, timed_out, peak_bytes=0):
    """The broken promises of one run (empty: it kept them all)."""
    if timed_out:
        return ["no end within %g s (killed)" % TIME_LIMIT]
    if status < 0:
        return ["killed by signal %d (%s)" % (-status, signal.Signals(-status).name)]
    problems = []
    if peak_bytes > PEAK_MEMORY_LIMIT:
        problems.append("peak memory %.1f GB, above %.0f GB" % (peak_bytes / 2 ** 30, PEAK_MEMORY_LIMIT / 2 ** 30))
    try:
        stderr = stderr_bytes.decode("utf-8")
    except UnicodeDecodeError as error:
        return problems + ["stderr is not UTF-8 text (%s)" % error]
    lines = stderr.split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    for number, line in enumerate(lines, 1):
        bad = next((i for i, c in enumerate(line) if not c.isprintable()), None)
        if bad is not None:
            c = line[bad]
            problems.append("stderr line %d has a character that is not printable, U+%04X %s (category %s), "
                            "at column %d: %r" % (number, ord(c), unicodedata.name(c, ""), unicodedata.category(c),
                                                  bad + 1, line[max(0, bad - 40):bad + 10]))
            break
    files = sorted(os.listdir(folder))
    leftovers = [f for f in files if ".tmp-" in f]
    if leftovers:
        problems.append("temporary files left: %s" % ", ".join(leftovers))
    if status == 0:
        if output not in files:
            problems.append("status 0 without the output %s" % output)
        stray = [line for line in lines if not line.startswith("msii: ")]
        if stray:
            problems.append("stderr line not starting 'msii: ': %r" % stray[0][:300])
    elif status == 1:
        if len(lines) != 1 or not stderr.endswith("\n"):
            problems.append("status 1 with %d stderr lines instead of one" % len(lines))
        if not lines or not lines[0].startswith("msii: error: "):
            problems.append("status 1 without a line 'msii: error: ...'")
        extra = [f for f in files if f not in inputs and ".tmp-" not in f]
        if extra:
            problems.append("status 1 but files written: %s" % ", ".join(extra))
    elif status == 2:
        problems.append("status 2 (wrong usage) for a correct command line")
    else:
        problems.append("status %d (neither 0 nor 1)" % status)
    return problems


class Run:
    """One mutant being computed by msii in its own folder."""

    def __init__(self, msii, mutant, work):
        self.mutant = mutant
        self.raster = mutant.format in RASTER_FORMATS
        self.output = "out.tif" if self.raster else "out.ply"
        self.folder = os.path.join(work, mutant.name)
        os.makedirs(self.folder)
        for name, data in [(mutant.name, mutant.data)] + list(mutant.companions.items()):
            with open(os.path.join(self.folder, name), "wb") as f:
                f.write(data)
        self.inputs = [mutant.name] + list(mutant.companions)
        self.command = command(msii, mutant.name, SEEDS[mutant.seed], self.raster)
        self.process = Process(self.command, self.folder)

    def poll(self):
        return self.process.poll()

    def result(self):
        p = self.process
        stderr = p.stderr()
        problems = judge(p.status, stderr, self.folder, self.inputs, self.output, p.timed_out, p.peak_bytes)
        return {"name": self.mutant.name, "format": self.mutant.format, "seed": self.mutant.seed,
                "mutation": "; ".join(self.mutant.notes), "status": p.status, "stderr": stderr,
                "problems": problems, "seconds": p.seconds, "peak_bytes": p.peak_bytes,
                "command": " ".join(os.path.basename(c) if i == 0 else c for i, c in enumerate(self.command))}


def keep_failure(result, item, keep):
    os.makedirs(keep, exist_ok=True)
    for name in item.inputs:
        shutil.copy(os.path.join(item.folder, name), keep)
    with open(os.path.join(keep, result["name"] + ".txt"), "w") as f:
        f.write(report(result) + "\n")


def report(result):
    text = ["FAIL %s: %s" % (result["name"], "; ".join(result["problems"])),
            "  mutation: %s" % result["mutation"],
            "  command:  %s" % result["command"],
            "  status:   %s after %.1f s, peak memory %.0f MB" % (result["status"], result["seconds"],
                                                                   result["peak_bytes"] / 2 ** 20)]
    for line in result["stderr"].decode("utf-8", "backslashreplace").split("\n"):
        if line:
            text.append("  stderr:   %r" % line[:500] if not line.isprintable() else "  stderr:   %s" % line[:500])
    return "\n".join(text)


def run(msii, count, seed, formats=FORMATS, jobs=2, keep=None, only=None, log=print):
    """Computes @p count mutants per format (or the mutants @p only) and returns one result
    per mutant, in order."""
    mutants = [(fmt, k) for fmt in formats for k in (only if only is not None else range(count))]
    results = []
    running = []
    work = tempfile.mkdtemp(prefix="msii-fuzz-")
    try:
        queue = list(mutants)
        while queue or running:
            while queue and len(running) < jobs:
                fmt, k = queue.pop(0)
                running.append(Run(msii, make_mutant(fmt, k, seed), work))
            time.sleep(0.005)
            for item in [r for r in running if r.poll()]:
                running.remove(item)
                result = item.result()
                results.append(result)
                if result["problems"]:
                    log(report(result))
                    if keep:
                        keep_failure(result, item, keep)
                shutil.rmtree(item.folder, ignore_errors=True)
    finally:
        for item in running:
            item.process.popen.kill()
            item.process.poll(block=True)
        shutil.rmtree(work, ignore_errors=True)
    order = {(fmt, k): i for i, (fmt, k) in enumerate(mutants)}
    results.sort(key=lambda r: order[(r["format"], int(r["name"].rsplit("-", 1)[1].split(".")[0]))])
    return results


def summary(results, seconds):
    per_format = {}
    for r in results:
        per_format[r["format"]] = per_format.get(r["format"], 0) + 1
    failed = sum(1 for r in results if r["problems"])
    status0 = sum(1 for r in results if r["status"] == 0)
    status1 = sum(1 for r in results if r["status"] == 1)
    text = ("fuzz: %d mutants (%s): %d passed, %d failed; status 0: %d, status 1: %d; %.1f s"
            % (len(results), ", ".join("%s %d" % kv for kv in per_format.items()), len(results) - failed, failed,
               status0, status1, seconds))
    if results:  # the near misses: the runs closest to the limits
        slowest = max(results, key=lambda r: r["seconds"])
        heaviest = max(results, key=lambda r: r["peak_bytes"])
        text += "; slowest %s %.1f s, most memory %s %.0f MB" % (slowest["name"], slowest["seconds"], heaviest["name"],
                                                                 heaviest["peak_bytes"] / 2 ** 20)
    return text


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--msii", default=os.environ.get("MSII_EXE"), help="the msii program (default: $MSII_EXE)")
    parser.add_argument("--count", type=int, default=100, help="mutants per format (default 100)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the mutations (default 1)")
    parser.add_argument("--format", default="all", choices=FORMATS + ("all",), help="which seeds (default all)")
    parser.add_argument("--keep", metavar="DIR", help="copy failing mutants, with a report each, to DIR")
    parser.add_argument("--jobs", type=int, default=2, help="runs at once (default 2)")
    parser.add_argument("--only", metavar="K,...", help="only these mutants of each format (to make a failure again)")
    parser.add_argument("--show", action="store_true", help="print every mutant's mutation and outcome")
    args = parser.parse_args()
    if not args.msii:
        parser.error("give --msii or set MSII_EXE")
    formats = FORMATS if args.format == "all" else (args.format,)
    only = [int(k) for k in args.only.split(",")] if args.only else None
    start = time.monotonic()
    results = run(os.path.abspath(args.msii), args.count, args.seed, formats, args.jobs, args.keep, only)
    if args.show:
        for r in results:
            first = r["stderr"].decode("utf-8", "backslashreplace").strip().split("\n")[-1][:160]
            print("%s status %s %.2f s %.0f MB | %s | %s" % (r["name"], r["status"], r["seconds"], r["peak_bytes"] / 2 ** 20,
                                                            r["mutation"], first))
    print(summary(results, time.monotonic() - start))
    sys.exit(0 if results and not any(r["problems"] for r in results) else 1)


if __name__ == "__main__":
    main()

"""A minimal OpenEXR reader (single part, scanlines, float or half channels, no or ZIP/ZIPS
compression): enough to read what `btf eval` writes, without osgBTF's own reader, so that the
tests compare the Python module against the btf tool through an independent path."""
import struct
import zlib

import numpy as np


def _undo_zip(data: bytes) -> bytes:
    # Predictor: each byte but the first was stored as the difference to the previous one
    # plus 128.
    raw = np.frombuffer(zlib.decompress(data), dtype=np.uint8).astype(np.int64)
    t = np.empty_like(raw)
    t[0] = raw[0]
    t[1:] = raw[1:] - 128
    t = np.cumsum(t) % 256
    # The writer put the even bytes in the first half, the odd ones in the second.
    n = len(t)
    out = np.empty(n, dtype=np.uint8)
    half = (n + 1) // 2
    out[0::2] = t[:half]
    out[1::2] = t[half:]
    return out.tobytes()


def read_exr(path):
    """-> (height, width, channels) float32, channels in the file's (alphabetical) order, and
    their names."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:4] != b"\x76\x2f\x31\x01":
        raise ValueError(f"{path}: not an OpenEXR file")
    version = struct.unpack_from("<I", data, 4)[0]
    if version & 0x1200:  # tiled or multi-part
        raise ValueError(f"{path}: tiled or multi-part files are not read here")
    pos = 8
    header = {}
    while data[pos] != 0:
        end = data.index(b"\0", pos)
        name = data[pos:end].decode()
        pos = end + 1
        end = data.index(b"\0", pos)
        kind = data[pos:end].decode()
        pos = end + 1
        (size,) = struct.unpack_from("<i", data, pos)
        pos += 4
        header[name] = (kind, data[pos : pos + size])
        pos += size
    pos += 1
    channels = []
    chlist = header["channels"][1]
    p = 0
    while chlist[p] != 0:
        end = chlist.index(b"\0", p)
        name = chlist[p:end].decode()
        p = end + 1
        pixel_type, _, xs, ys = struct.unpack_from("<iB3xii", chlist, p)
        p += 16
        if xs != 1 or ys != 1:
            raise ValueError("subsampled channels are not read here")
        channels.append((name, pixel_type))
    compression = header["compression"][1][0]
    x0, y0, x1, y1 = struct.unpack("<4i", header["dataWindow"][1])
    width, height = x1 - x0 + 1, y1 - y0 + 1
    lines = {0: 1, 2: 1, 3: 16}.get(compression)
    if lines is None:
        raise ValueError(f"{path}: compression {compression} is not read here")
    chunks = (height + lines - 1) // lines
    offsets = struct.unpack_from(f"<{chunks}Q", data, pos)
    dtypes = {1: np.dtype("<f2"), 2: np.dtype("<f4")}
    out = np.zeros((height, width, len(channels)), dtype=np.float32)
    for offset in offsets:
        y, size = struct.unpack_from("<ii", data, offset)
        block = data[offset + 8 : offset + 8 + size]
        count = min(lines, y1 + 1 - y)
        expected = count * width * sum(dtypes[t].itemsize for _, t in channels)
        if compression != 0 and size < expected:
            block = _undo_zip(block)
        q = 0
        for row in range(count):
            for c, (_, t) in enumerate(channels):
                n = width * dtypes[t].itemsize
                out[y - y0 + row, :, c] = np.frombuffer(block[q : q + n], dtype=dtypes[t])
                q += n
    return out, [name for name, _ in channels]


def read_rgb(path):
    """The R, G, B channels as (height, width, 3) float32."""
    image, names = read_exr(path)
    return np.stack([image[:, :, names.index(c)] for c in "RGB"], axis=-1)

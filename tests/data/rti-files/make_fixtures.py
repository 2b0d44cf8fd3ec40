#!/usr/bin/env python3
"""Writes the RTI file fixtures of tests/materials_rti_files_test.cpp into this folder, with
numpy and Pillow (libjpeg) only: nothing of osgBTF. Run from anywhere:

    /usr/bin/python3 tests/data/rti-files/make_fixtures.py   (numpy, Pillow)

Layouts (docs/formats.md 8.1.1 and 8.4; the sources the notes cite: relight's writer and
OpenLIME's reader for the web layout, RTIViewer, ptmlib and relight for the PTM JPEG streams).

JPEG exactness: every image is written at quality 100 without chroma subsampling. A greyscale
plane of one value is exact (quantisation step 1 of the DC term, no colour transform); an RGB
plane goes through YCbCr and, where it is not uniform, through AC terms, so its decoded bytes may
differ from the intended ones. The script decodes every plane again (Pillow, libjpeg) and fails
if any byte is more than 1 away from the intended one; the test allows 2 bytes.
"""
import io
import json
import os

import numpy as np
from PIL import Image

HERE = os.path.dirname(os.path.abspath(__file__))
W, H = 4, 3


def jpeg_bytes(array):
    """array: H x W (grey) or H x W x 3 uint8, row 0 first in the file."""
    image = Image.fromarray(np.asarray(array, dtype=np.uint8))
    out = io.BytesIO()
    image.save(out, format="JPEG", quality=100, subsampling=0)
    data = out.getvalue()
    decoded = np.asarray(Image.open(io.BytesIO(data)), dtype=int)
    worst = int(np.max(np.abs(decoded - np.asarray(array, dtype=int))))
    assert worst <= 1, f"JPEG round trip off by {worst}"
    return data


def rows(top, rest):
    """An RGB plane: the top image row `top`, the two rows below `rest` (each an RGB triple)."""
    a = np.zeros((H, W, 3), dtype=np.uint8)
    a[0, :, :] = top
    a[1:, :, :] = rest
    return a


def uniform(rgb):
    return rows(rgb, rgb)


def relight(folder, info, planes):
    path = os.path.join(HERE, folder)
    os.makedirs(path, exist_ok=True)
    for name in os.listdir(path):
        os.remove(os.path.join(path, name))
    with open(os.path.join(path, "info.json"), "w") as f:
        json.dump(info, f, indent=1)
        f.write("\n")
    for j, plane in enumerate(planes):
        with open(os.path.join(path, f"plane_{j}.jpg"), "wb") as f:
            f.write(jpeg_bytes(plane))


LIGHTS = [0.6, 0.0, 0.8, 0.0, 0.6, 0.8, 0.0, 0.0, 1.0]


def relight_fixtures():
    # ptm, lrgb, 9 planes: plane_0 the base colour, plane_1 luminance (1, x, y), plane_2
    # (x^2, xy, y^2). Base colour: top row (255, 153, 51), the rows below (51, 102, 204).
    # Luminance planes 3..5: scale 2, bias 0.5: byte 204 -> 0.6, 255 -> 1.0, 153 -> 0.2,
    # 102 -> -0.2. Planes 6..8: scale 1, bias 0: byte 51 -> 0.2, 0 -> 0.
    relight(
        "relight-ptm-lrgb",
        {"width": W, "height": H, "format": "jpg", "type": "ptm", "colorspace": "lrgb",
         "lights": LIGHTS, "nplanes": 9, "quality": 100,
         "materials": [{"scale": [1, 1, 1, 2, 2, 2, 1, 1, 1],
                        "bias": [0, 0, 0, 0.5, 0.5, 0.5, 0, 0, 0]}]},
        [rows((255, 153, 51), (51, 102, 204)),
         rows((204, 255, 153), (204, 255, 102)),
         uniform((51, 0, 0))])
    # ptm, rgb, 9 planes (first degree): plane_j = term j (1, x, y) of R, G, B; scale 1, bias 0
    # for the constant term, scale 2 and bias 0.5 for x and y.
    relight(
        "relight-ptm-rgb",
        {"width": W, "height": H, "format": "jpg", "type": "ptm", "colorspace": "rgb",
         "nplanes": 9, "quality": 100,
         "materials": [{"scale": [1, 1, 1, 2, 2, 2, 2, 2, 2],
                        "bias": [0, 0, 0, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5]}]},
        [uniform((153, 102, 51)),
         uniform((204, 153, 153)),
         rows((255, 153, 153), (153, 153, 153))])
    # hsh, rgb, 12 planes: 4 terms, plane_j = term j of R, G, B; scale 1, bias 0.
    relight(
        "relight-hsh-rgb",
        {"width": W, "height": H, "format": "jpg", "type": "hsh", "colorspace": "rgb",
         "lights": LIGHTS, "nplanes": 12, "quality": 100,
         "materials": [{"scale": [1] * 12, "bias": [0] * 12}]},
        [uniform((255, 153, 51)),
         uniform((51, 0, 0)),
         rows((102, 51, 0), (0, 0, 0)),
         uniform((0, 0, 0))])
    # hsh, lrgb, 12 planes: base colour + 9 luminance terms. Base colour scale 1, bias 0;
    # luminance scale 2, bias 0.5 (byte 153 -> 0.2, 204 -> 0.6, 102 -> -0.2).
    relight(
        "relight-hsh-lrgb",
        {"width": W, "height": H, "format": "jpg", "type": "hsh", "colorspace": "lrgb",
         "nplanes": 12, "quality": 100,
         "materials": [{"scale": [1, 1, 1] + [2] * 9, "bias": [0, 0, 0] + [0.5] * 9}]},
        [uniform((255, 102, 51)),
         uniform((204, 153, 153)),
         uniform((153, 153, 153)),
         uniform((102, 153, 153))])
    # rbf, mrgb, 3 planes (relight's PCA type; docs/formats.md 8.4): one JPEG, coefficient
    # a_p = (byte / 255 - 0.5) * 1: top row (204, 153, 51) -> (0.3, 0.1, -0.3), the rows below
    # (255, 102, 153) -> (0.5, -0.1, 0.1). Three lights (nodes). Basis, p-major, per node RGB:
    # p = 0 the mean profile in 0..255 (node 0 (51, 102, 153) = (0.2, 0.4, 0.6), node 1 0.4 grey,
    # node 2 (204, 153, 0) = (0.8, 0.6, 0)); p >= 1: 127 + range_p E_p, ranges 127, 63.5, 254:
    # E_1 = (1, 0, 0), (0, 1, 0), (0, 0, -1); E_2 = 0, 0, (2, 0, 0); E_3 = (-0.5, 0, 0), 0,
    # (0, 0.5, 0). sigma 0.2: at a node the others weigh exp(-0.4 / 0.04) / (1 + ...) = 4.5e-5
    # < 0.001 and are dropped, so the value there is the node's profile.
    relight(
        "relight-rbf-mrgb",
        {"width": W, "height": H, "format": "jpg", "type": "rbf", "colorspace": "mrgb",
         "sigma": 0.2, "lights": LIGHTS, "nplanes": 3, "quality": 100,
         "basis": [51, 102, 153, 102, 102, 102, 204, 153, 0,
                   254, 127, 127, 127, 254, 127, 127, 127, 0,
                   127, 127, 127, 127, 127, 127, 254, 127, 127,
                   0, 127, 127, 127, 127, 127, 127, 254, 127],
         "materials": [{"range": [127, 63.5, 254], "scale": [1, 1, 1],
                        "bias": [0.5, 0.5, 0.5]}]},
        [rows((204, 153, 51), (255, 102, 153))])
    # bilinear, mrgb, 3 planes on a 2 x 2 octahedral grid (nodes (0, 0), (1, 0), (0, 1), (1, 1)):
    # mean profile red, green, blue, black; E_1 = (1, 1, 1) at every node (range 127), E_2 = E_3
    # = 0. Uniform plane: a = (0.3, 0, 0) (bytes 204, 127.5 -> 128 and 128: scale 1, bias 0.5
    # gives a_2 = a_3 = 0.002, times E = 0).
    relight(
        "relight-bilinear-mrgb",
        {"width": W, "height": H, "format": "jpg", "type": "bilinear", "resolution": 2,
         "colorspace": "mrgb", "lights": LIGHTS, "nplanes": 3, "quality": 100,
         "basis": [255, 0, 0, 0, 255, 0, 0, 0, 255, 0, 0, 0] + [254] * 12 + [127] * 24,
         "materials": [{"range": [127, 127, 127], "scale": [1, 1, 1],
                        "bias": [0.5, 0.5, 0.5]}]},
        [uniform((204, 128, 128))])
    # rbf, mycc (relight's luminance + chroma variant): "yccplanes" [2, 1, 1] instead of
    # "nplanes" (4 planes, 2 JPEGs). The profiles are (Y, Co, Cg); planes 0..2 interleave Y, Co,
    # Cg (relight's renderer reads channel q % 3 of plane q's basis), plane 3 is Y (channel 0
    # only): the other channels of those basis entries hold values the renderer ignores. Only
    # node 2 is non-zero: mean (153, 51, 0) = (0.6, 0.2, 0); E_1 = (1, ignored, ignored), E_2 =
    # (ignored, 1, 0), E_3 = (0, 0, 1), E_4 = (1, ignored, ignored) (range 127). Coefficients
    # (scale 1, bias 0.5): plane_0 (204, 153, 102) -> (0.3, 0.1, -0.1), plane_1 153 -> 0.1.
    # At node 2: (Y, Co, Cg) = (1.0, 0.3, -0.1) -> RGB (1.2, 0.95, 0.9) (YCoCg's inverse).
    z = [127, 127, 127] * 2
    relight(
        "relight-rbf-mycc",
        {"width": W, "height": H, "format": "jpg", "type": "rbf", "colorspace": "mycc",
         "sigma": 0.2, "lights": LIGHTS, "yccplanes": [2, 1, 1], "quality": 100,
         "basis": [0, 0, 0, 0, 0, 0, 153, 51, 0]
                  + z + [254, 200, 10]
                  + z + [50, 254, 127]
                  + z + [127, 127, 254]
                  + z + [254, 254, 254],
         "materials": [{"range": [127] * 4, "scale": [1] * 4, "bias": [0.5] * 4}]},
        [uniform((204, 153, 102)), uniform((153, 128, 128))])
    # A plane of the wrong size, for the hostile tests.
    with open(os.path.join(HERE, "wrong-size-5x3.jpg"), "wb") as f:
        f.write(jpeg_bytes(np.full((3, 5, 3), 128, dtype=np.uint8)))


def ptm_jpeg(name, fmt, scale, bias, streams, order, reference, transforms, side):
    """streams: the stored grey value of each (uniform planes, exact through JPEG); side: per
    stream a list of (position, value) records."""
    n = len(streams)
    data = [jpeg_bytes(np.full((H, W), v, dtype=np.uint8)) for v in streams]
    info = [b"".join(bytes([(p >> 24) & 255, (p >> 16) & 255, (p >> 8) & 255, p & 255, v])
                     for p, v in side.get(i, [])) for i in range(n)]
    line = lambda values: " ".join(str(v) for v in values) + "\n"
    header = ("PTM_1.2\n" + fmt + "\n" + f"{W}\n{H}\n" + line(scale) + line(bias) + "100\n" +
              line(transforms) + line([0] * n) + line([0] * n) + line(order) + line(reference) +
              line([len(d) for d in data]) + line([len(s) for s in info]))
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(header.encode())
        for d, s in zip(data, info):
            f.write(d)
            f.write(s)


def ptm_fixtures():
    # JPEG_LRGB: streams a0..a5 (u^2, v^2, uv, u, v, 1), then R, G, B. Final values (0..255
    # units after the scale and bias): a0 = 10, a1 = a2 = 0, a3 = (100 - 50) * 2 = 100,
    # a4 = 0 but 50 at position 0 and -50 at position 7, a5 = 150; colour (255, 128, 0).
    # Stream 5 is decoded first (150); stream 3 predicts from it: 150 + 78 - 128 = 100; stream 0
    # predicts from stream 3 inverted: (255 - 100) + 239 - 128 = 266 = 10 mod 256.
    ptm_jpeg("jpeg-lrgb.ptm", "PTM_FORMAT_JPEG_LRGB",
             scale=[1, 1, 1, 2, 1, 1], bias=[0, 0, 0, 50, 128, 0],
             streams=[239, 0, 0, 78, 128, 150, 255, 128, 0],
             order=[2, 3, 4, 1, 5, 0, 6, 7, 8],
             reference=[3, -1, -1, 5, -1, -1, -1, -1, -1],
             transforms=[1, 0, 0, 0, 0, 0, 0, 0, 0],
             side={4: [(0, 178), (7, 78)]})
    # JPEG_RGB: streams R a0..a5, G a0..a5, B a0..a5; scale 1, bias 0. R: a3 = 100, a5 = 100;
    # G: a4 = 100, a5 = 50; B: a0 = 200, a5 = 0 but 255 at position 11 (the last pixel: top
    # right, the streams' first scanline being the bottom row).
    streams = [0] * 18
    streams[3] = streams[5] = 100
    streams[6 + 4], streams[6 + 5] = 100, 50
    streams[12 + 0] = 200
    ptm_jpeg("jpeg-rgb.ptm", "PTM_FORMAT_JPEG_RGB", scale=[1] * 6, bias=[0] * 6,
             streams=streams, order=list(range(18)), reference=[-1] * 18,
             transforms=[0] * 18, side={17: [(11, 255)]})


relight_fixtures()
ptm_fixtures()

"""Measured BTFs: the sample, loading zips and UBO2014 files, images, texels, errors, leaks."""
import gc
import os
import weakref

import numpy as np
import pytest

import osgbtf
from conftest import SIZE


def test_sample_in_memory_has_the_bonn_directions():
    btf = osgbtf.sample(8)
    assert (btf.width, btf.height) == (8, 8)
    assert btf.views.shape == (81, 3) and btf.lights.shape == (81, 3)
    assert btf.views.dtype == np.float32
    np.testing.assert_allclose(np.linalg.norm(btf.views, axis=1), 1, atol=1e-6)
    # The Bonn set's first direction is the zenith; theta of every direction is below 90.
    np.testing.assert_allclose(btf.views[0], [0, 0, 1], atol=1e-6)
    assert (btf.view_angles[:, 0] < 90).all()
    # Vectors and angles describe the same directions.
    theta = np.radians(btf.light_angles[:, 0])
    np.testing.assert_allclose(btf.lights[:, 2], np.cos(theta), atol=1e-6)
    assert btf.in_memory and btf.path == ""


def test_loading_the_written_sample_gives_the_sample_exactly(sample_btf):
    memory = osgbtf.sample(SIZE)
    assert (sample_btf.width, sample_btf.height) == (SIZE, SIZE)
    for view, light in [(0, 0), (10, 40), (80, 80)]:
        assert np.array_equal(sample_btf.image(view, light), memory.image(view, light))
    assert np.array_equal(sample_btf.views, memory.views)


def test_image_and_texels_are_the_same_values(sample_btf):
    # image() reads whole images, texels() texel ABRDFs: two read paths of the same data.
    block = sample_btf.texels(2, 3, 5, 4)
    assert block.shape == (4, 5, 81, 81, 3)
    image = sample_btf.image(7, 20)
    # image rows are top-down, texel y counts from the bottom.
    for j in range(4):
        for i in range(5):
            y = 3 + j
            assert np.array_equal(block[j, i, 7, 20], image[SIZE - 1 - y, 2 + i])
    values = sample_btf.image(3, 3)
    assert values.min() >= 0 and values.max() <= 1 and values.max() > 0.05


def test_image_is_a_view_of_one_buffer_not_a_copy(sample_btf):
    image = sample_btf.image(1, 2)
    assert image.base is not None and image.strides[0] < 0  # the flipped rows of one buffer
    assert not image.flags.owndata


def test_bad_input_raises_with_the_one_line_message(tmp_path):
    missing = str(tmp_path / "missing.zip")
    with pytest.raises(osgbtf.Error, match=r"missing\.zip: no such file"):
        osgbtf.load(missing)
    empty = tmp_path / "empty.zip"
    empty.write_bytes(b"")
    with pytest.raises(osgbtf.Error) as error:
        osgbtf.load(str(empty))
    assert str(error.value).startswith(str(empty)) and "\n" not in str(error.value)
    with pytest.raises(ValueError, match="decode must be one of"):
        osgbtf.load(missing, decode="log")
    btf = osgbtf.sample(4)
    with pytest.raises(IndexError, match="view index 81"):
        btf.image(81, 0)
    with pytest.raises(IndexError, match="not inside"):
        btf.texels(0, 0, 5, 1)


def test_ubo2014_is_decoded_on_demand_within_a_small_memory_limit(ubo2014_file, sample_btf):
    before = osgbtf.load(ubo2014_file)  # default limit
    default_limit = osgbtf.memory_limit()
    limit = 2 * 1024 * 1024
    try:
        btf = osgbtf.load(ubo2014_file, memory_limit=limit)
        assert not btf.in_memory
        # The whole BTF would need more than the limit; it is never decoded whole.
        assert btf.decoded_bytes > limit
        image = btf.image(40, 12)
        assert image.shape == (SIZE, SIZE, 3)
        # An 8-component factorisation of the sample: close to the measured image.
        measured = sample_btf.image(40, 12)
        assert np.abs(image - measured).mean() < 0.02
        assert np.array_equal(image, before.image(40, 12))
        block = btf.texels(0, 0, 2, 2)
        assert block.shape == (2, 2, 81, 81, 3)
        assert np.array_equal(block[1, 0, 40, 12], image[SIZE - 2, 0])
        # All texels at once would pass the limit: refused before allocating.
        with pytest.raises(osgbtf.Error, match="memory limit"):
            btf.texels(0, 0, SIZE, SIZE)
        assert osgbtf.memory_limit() == limit
    finally:
        osgbtf.load(ubo2014_file, memory_limit=default_limit)
    assert osgbtf.memory_limit() == default_limit


def rss_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def test_no_leak_over_1000_loads(ubo2014_file):
    # Warm up (allocator pools, the loaders' first use), then 1000 loads with an image each.
    for _ in range(50):
        osgbtf.load(ubo2014_file).image(0, 0)
    gc.collect()
    before = rss_bytes()
    for _ in range(1000):
        btf = osgbtf.load(ubo2014_file)
        ref = weakref.ref(btf)
        btf.image(3, 4)
        del btf
        assert ref() is None  # nothing (no array, no cycle) keeps a Btf alive
    gc.collect()
    grown = rss_bytes() - before
    # One load holds ~8 factors x (16 x 16 + 81 x 81) floats, ~0.25 MB: a leak of each would
    # grow by ~250 MB.
    assert grown < 20 * 1024 * 1024, f"RSS grew by {grown} bytes over 1000 loads"

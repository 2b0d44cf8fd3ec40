"""Methods, fits, options, progress, interruption, the GIL."""
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import pytest

import osgbtf
from conftest import run_btf


def test_methods_are_the_registry_with_its_option_tables(btf_tool):
    methods = {m["name"]: m for m in osgbtf.methods()}
    for name in ["lambert", "laf", "slaf", "rf", "pca", "lpca", "lpca-revised", "fmf", "ptm"]:
        assert name in methods
    assert methods["lambert"]["baseline"]
    pca = {o["name"]: o for o in methods["pca"]["options"]}
    assert pca["components"]["type"] == "integer"
    assert pca["components"]["min"] == 1 and pca["components"]["max"] is None
    assert pca["storage"]["choices"] == ["unorm8", "half", "float"]
    # The same table `btf fit --help` prints: every method, every option line.
    help_text = run_btf(btf_tool, "fit", "--help")
    for method in methods.values():
        assert method["name"] in help_text
        for option in method["options"]:
            assert option["name"] in help_text
    # The docstring of fit is made from the same table.
    assert methods["rf"]["description"] in osgbtf.fit.__doc__


def test_fit_gives_a_material_with_its_options(sample_btf, pca):
    assert pca.method == "pca"
    assert pca.options["components"] == "8"
    assert pca.options["storage"] == "unorm8"  # the default, recorded
    assert (pca.width, pca.height) == (sample_btf.width, sample_btf.height)
    assert pca.bytes_per_texel > 0
    lambert = osgbtf.fit(sample_btf, "lambert")
    assert lambert.method == "lambert"
    e_pca, e_lambert = osgbtf.error(sample_btf, pca), osgbtf.error(sample_btf, lambert)
    assert e_pca["texels"] == sample_btf.width * sample_btf.height
    # Eight components of the sample beat a plain lit texture by far.
    assert e_pca["average"] < 0.5 * e_lambert["average"]


def test_option_errors_are_value_errors_with_the_registry_message(sample_btf):
    with pytest.raises(ValueError, match=r"^pca: option components must be an integer >= 1, "
                                         r"got 0$"):
        osgbtf.fit(sample_btf, "pca", components=0)
    with pytest.raises(ValueError, match=r"pca: option lobes is unknown \(known: components, "
                                         r"storage\)"):
        osgbtf.fit(sample_btf, "pca", lobes=2)
    with pytest.raises(ValueError, match=r"unknown method 'pcb' \(known: .*pca"):
        osgbtf.fit(sample_btf, "pcb")
    with pytest.raises(ValueError, match="rf: option max-exponent must be"):
        osgbtf.fit(sample_btf, "rf", max_exponent=1000)


def test_progress_callback_hears_the_fit(sample_btf):
    calls = []
    osgbtf.fit(sample_btf, "rf", starts=1, iterations=5,
               progress=lambda label, done, total: calls.append((label, done, total)))
    assert calls, "the progress callback was never called"
    label, done, total = calls[-1]
    assert label == "rf fit" and done == total == sample_btf.width * sample_btf.height
    assert all(0 <= d <= t for _, d, t in calls)


def test_a_fit_stopped_from_python_raises_and_the_next_fit_runs(sample_btf):
    def stop(label, done, total):
        return False

    with pytest.raises(KeyboardInterrupt):
        osgbtf.fit(sample_btf, "rf", starts=1, iterations=5, progress=stop)

    class Mine(Exception):
        pass

    def fail(label, done, total):
        raise Mine("from the callback")

    with pytest.raises(Mine, match="from the callback"):
        osgbtf.fit(sample_btf, "rf", starts=1, iterations=5, progress=fail)
    # Nothing of the stop is left behind.
    material = osgbtf.fit(sample_btf, "rf", starts=1, iterations=5)
    assert material.method == "rf"


def test_ctrl_c_stops_a_long_fit_cleanly(sample_zip):
    # A real SIGINT, sent while the fit runs; the child prints what it caught.
    script = textwrap.dedent(f"""
        import os, signal, sys, threading, time
        import osgbtf
        btf = osgbtf.load({sample_zip!r})
        sent = []
        def progress(label, done, total):
            if not sent:
                sent.append(time.monotonic())
                os.kill(os.getpid(), signal.SIGINT)
        start = time.monotonic()
        try:
            osgbtf.fit(btf, "rf", starts=3, iterations=400, progress=progress)
            print("finished")
        except KeyboardInterrupt:
            print("interrupted", round(time.monotonic() - sent[0], 2))
        # Python's own handler is back: a second Ctrl-C is an ordinary KeyboardInterrupt.
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(1)
        except KeyboardInterrupt:
            print("handler restored")
        print(osgbtf.fit(btf, "lambert").method)
    """)
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                            timeout=300, env=os.environ)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.split("\n")
    assert lines[0].startswith("interrupted"), result.stdout
    assert float(lines[0].split()[1]) < 5  # it stops at the next progress step
    assert lines[1] == "handler restored" and lines[2] == "lambert"


def test_fits_release_the_gil(sample_btf):
    ticks = 0
    done = threading.Event()

    def work():
        osgbtf.fit(sample_btf, "rf", starts=1, iterations=30)
        done.set()

    thread = threading.Thread(target=work)
    thread.start()
    start = time.monotonic()
    while not done.is_set():
        ticks += 1
        time.sleep(0.001)
    thread.join()
    elapsed = time.monotonic() - start
    # The main thread kept running Python all through the fit.
    assert elapsed > 0.1 and ticks > elapsed * 100, (ticks, elapsed)


def test_options_from_python_values(sample_btf):
    m = osgbtf.fit(sample_btf, "pca", components=np.int64(3), storage="half")
    assert m.options == {"components": "3", "storage": "half"}

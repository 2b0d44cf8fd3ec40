"""Shared fixtures: a small sample written as files, the btf tool, a UBO2014 file."""
import os
import pathlib
import shutil
import subprocess
import sys

import pytest

sys.path.insert(0, os.path.dirname(__file__))  # exr.py

import osgbtf  # noqa: E402  (PYTHONPATH=build/python, as ctest's python.pytest sets it)

SIZE = 16  # texels per side of the test sample: every method fits it in seconds


@pytest.fixture(scope="session")
def btf_tool():
    """The btf executable the tests compare against: OSGBTF_BTF (ctest sets it), else the one
    beside the module in the build tree, else the one on PATH."""
    tool = os.environ.get("OSGBTF_BTF")
    if not tool:
        here = pathlib.Path(osgbtf.__file__).resolve().parent
        candidate = here.parent / "bin" / "btf"
        tool = str(candidate) if candidate.exists() else shutil.which("btf")
    if not tool:
        pytest.skip("no btf executable (set OSGBTF_BTF)")
    return tool


def run_btf(tool, *args):
    result = subprocess.run([tool, *map(str, args)], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    return result.stdout


@pytest.fixture(scope="session")
def data_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("osgbtf")


@pytest.fixture(scope="session")
def sample_zip(data_dir):
    """The sample with float EXR members: loading it gives the in-memory sample exactly."""
    return osgbtf.sample(SIZE, path=str(data_dir / "sample.zip"), format="exr")


@pytest.fixture(scope="session")
def sample_btf(sample_zip):
    return osgbtf.load(sample_zip)


@pytest.fixture(scope="session")
def ubo2014_file(data_dir, sample_zip, btf_tool):
    """A UBO2014 FMF file written by `btf fit -m fmf -o x.btf` from the sample."""
    path = data_dir / "sample.btf"
    run_btf(btf_tool, "fit", sample_zip, "-m", "fmf", "--set", "components=8", "-o", path)
    return str(path)


@pytest.fixture(scope="session")
def pca(sample_btf):
    return osgbtf.fit(sample_btf, "pca", components=8)

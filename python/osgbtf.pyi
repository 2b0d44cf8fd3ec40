# Type stub of the osgbtf module (python/osgbtf.cpp), for editors and type checkers.
# The docstrings in the module itself come from the same method and option tables as
# `btf fit --help` (help(osgbtf.fit)); docs/python.md describes the API.
from os import PathLike
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, TypedDict, Union

import numpy as np
import numpy.typing as npt

__version__: str

FloatArray = npt.NDArray[np.float32]
#: (theta, phi) in degrees, or an (x, y, z) unit vector in the local frame (+Z normal).
Direction = Union[Tuple[float, float], Sequence[float], npt.ArrayLike]
#: progress(label, done, total): return False (or raise) to stop the work.
ProgressCallback = Callable[[str, int, int], Optional[bool]]

class Error(RuntimeError):
    """osgBTF's one-line errors ("<file>: <problem>")."""

class Btf:
    """A measured BTF (UBO2003/ATRIUM zip or folder in memory, or a UBO2014 file kept factored)."""
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def views(self) -> FloatArray:
        """(n, 3) unit view directions, in the data's index order."""
    @property
    def lights(self) -> FloatArray:
        """(n, 3) unit light directions, in the data's index order."""
    @property
    def view_angles(self) -> FloatArray:
        """(n, 2) theta, phi of the views in degrees."""
    @property
    def light_angles(self) -> FloatArray:
        """(n, 2) theta, phi of the lights in degrees."""
    @property
    def path(self) -> str: ...
    @property
    def in_memory(self) -> bool: ...
    @property
    def decoded_bytes(self) -> int: ...
    def image(self, view: int, light: int) -> FloatArray:
        """(height, width, 3) float32, rows top-down (a row-reversed view of the buffer)."""
    def texels(self, x: int, y: int, w: int, h: int) -> FloatArray:
        """(h, w, views, lights, 3) float32; [j, i] is texel (x + i, y + j), y from the bottom."""

class OptionSchema(TypedDict, total=False):
    name: str
    type: str  # "integer", "number", "enum", "bool"
    default: str
    allowed: str
    min: float
    max: Optional[float]
    choices: List[str]
    doc: str
    help: str

class MethodSchema(TypedDict):
    name: str
    description: str
    options: List[OptionSchema]
    baseline: bool
    can_fit: bool
    quick_fit_options: str

class ErrorSummary(TypedDict):
    average: float
    minimum: float
    maximum: float
    rmse: float
    psnr: float
    texels: int
    non_finite: int

class Material:
    """A fitted material of any method."""
    @property
    def method(self) -> str: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def options(self) -> Dict[str, str]: ...
    @property
    def fit_info(self) -> Dict[str, str]: ...
    @property
    def bytes_per_texel(self) -> float: ...
    @property
    def values_per_texel(self) -> float: ...
    @property
    def total_bytes(self) -> int: ...
    @property
    def mip_levels(self) -> int: ...
    @property
    def views(self) -> FloatArray: ...
    @property
    def lights(self) -> FloatArray: ...
    @property
    def source_file(self) -> str: ...
    def evaluate(
        self,
        uv: npt.ArrayLike,
        view_dirs: npt.ArrayLike,
        light_dirs: npt.ArrayLike,
        filter: str = "nearest",
    ) -> FloatArray:
        """(N, 2) uv, (N, 3) view and light unit vectors (or one row each) -> (N, 3)."""
    def image(self, view: Direction, light: Direction) -> FloatArray:
        """CPU image, (height, width, 3), rows top-down: what `btf eval --cpu` writes."""
    def render(
        self, view: Direction, light: Direction, size: Union[None, int, Tuple[int, int]] = None
    ) -> Tuple[FloatArray, float]:
        """GPU image through the method's shader (headless EGL) and its largest GPU-CPU
        difference; size None: one pixel per texel (`btf eval`), else that many pixels."""
    def save(self, path: Union[str, PathLike[str]]) -> None: ...

def load(
    path: Union[str, PathLike[str]],
    memory_limit: Union[None, int, str] = None,
    decode: str = "linear",
    storage: str = "float",
) -> Btf: ...
def memory_limit() -> int: ...
def sample(
    size: int = 64,
    variation: float = 0.0,
    path: Union[None, str, PathLike[str]] = None,
    format: str = "jpg",
    quality: int = 95,
    weave_repeats: int = 2,
) -> Union[Btf, str]: ...
def methods() -> List[MethodSchema]: ...
def fit(
    btf: Btf,
    method: str,
    *,
    progress: Optional[ProgressCallback] = None,
    mipmap: bool = False,
    **options: Any,
) -> Material: ...
def open_material(path: Union[str, PathLike[str]], storage: str = "half") -> Material: ...
def error(btf: Btf, material: Material, error_texels: int = -1) -> ErrorSummary: ...
def error_of(
    btf: Btf,
    model: Callable[[FloatArray, FloatArray, FloatArray], npt.ArrayLike],
    error_texels: int = -1,
    batch_texels: int = 64,
) -> ErrorSummary: ...
def compare(
    btf: Btf,
    methods: Sequence[str] = ("all",),
    holdout_fraction: float = 0.1,
    options: Dict[str, Dict[str, Any]] = {},
    report: Union[None, str, PathLike[str]] = None,
    error_texels: int = -1,
    progress: Optional[ProgressCallback] = None,
) -> List[Dict[str, Any]]: ...

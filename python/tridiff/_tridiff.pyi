"""Type stubs of the extension module (python/src); use the `tridiff` package instead."""
from typing import Any, Literal, overload

import numpy as np
import numpy.typing as npt

class LinAlgError(np.linalg.LinAlgError):
    system: tuple[int, ...] | None
    row: int | None

solver_methods: tuple[str, ...]

@overload
def solve(
    a: npt.ArrayLike, b: npt.ArrayLike, c: npt.ArrayLike, d: npt.ArrayLike, axis: int = -1,
    method: str = "auto", periodic: bool = False, threads: int = 0,
    out: np.ndarray | None = None, info: Literal[False] = False,
) -> np.ndarray: ...
@overload
def solve(
    a: npt.ArrayLike, b: npt.ArrayLike, c: npt.ArrayLike, d: npt.ArrayLike, axis: int = -1,
    method: str = "auto", periodic: bool = False, threads: int = 0,
    out: np.ndarray | None = None, *, info: Literal[True],
) -> tuple[np.ndarray, npt.NDArray[np.int64]]: ...
@overload
def solve_diffusion(
    beta: npt.ArrayLike, d: npt.ArrayLike, axis: int = -1, method: str = "auto",
    periodic: bool = False, threads: int = 0, out: np.ndarray | None = None,
    info: Literal[False] = False,
) -> np.ndarray: ...
@overload
def solve_diffusion(
    beta: npt.ArrayLike, d: npt.ArrayLike, axis: int = -1, method: str = "auto",
    periodic: bool = False, threads: int = 0, out: np.ndarray | None = None, *,
    info: Literal[True],
) -> tuple[np.ndarray, npt.NDArray[np.int64]]: ...
class Factors:
    """LU factors of a batch of tridiagonal systems (tridiff.factor, tridiff.factor_diffusion)."""
    @property
    def shape(self) -> tuple[int, ...]: ...
    @property
    def axis(self) -> int: ...
    @property
    def dtype(self) -> np.dtype[Any]: ...
    @property
    def pivoted(self) -> npt.NDArray[np.bool_]: ...
    @property
    def nbytes(self) -> int: ...
    def solve(self, d: npt.ArrayLike, trans: Literal[0, 1, 2, "N", "T", "C"] = "N",
              threads: int = 0, out: np.ndarray | None = None) -> np.ndarray: ...
    def rcond(self, threads: int = 0) -> np.ndarray: ...
def factor(a: npt.ArrayLike, b: npt.ArrayLike, c: npt.ArrayLike, axis: int = -1,
           method: Literal["auto", "no-pivoting", "pivoting"] = "auto",
           threads: int = 0) -> Factors: ...
def factor_diffusion(beta: npt.ArrayLike, axis: int = -1, dtype: npt.DTypeLike = None,
                     threads: int = 0) -> Factors: ...
def _blur(image: npt.ArrayLike, sigma: float, method: str, border: str = "replicate",
          threads: int = 0) -> npt.NDArray[np.float32]: ...
def _blur_methods() -> list[dict[str, Any]]: ...
@overload
def dof(
    color: npt.ArrayLike, depth: npt.ArrayLike, *, focus: float = 3.2, f_number: float = 2.8,
    focal_length: float = 50.0, sensor_width: float = 36.0, max_coc: float = 64.0,
    method: str = "bokeh", layers: bool | None = None, in_focus: float = 1.0, threads: int = 0,
    return_coc: Literal[False] = False,
) -> npt.NDArray[np.float32]: ...
@overload
def dof(
    color: npt.ArrayLike, depth: npt.ArrayLike, *, focus: float = 3.2, f_number: float = 2.8,
    focal_length: float = 50.0, sensor_width: float = 36.0, max_coc: float = 64.0,
    method: str = "bokeh", layers: bool | None = None, in_focus: float = 1.0, threads: int = 0,
    return_coc: Literal[True],
) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]: ...
def _dof_methods() -> list[dict[str, Any]]: ...

"""Type stubs of the tridiff package (python/tridiff/__init__.py)."""
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from ._tridiff import Factors as Factors
from ._tridiff import LinAlgError as LinAlgError
from ._tridiff import dof as dof
from ._tridiff import factor as factor
from ._tridiff import factor_diffusion as factor_diffusion
from ._tridiff import solve as solve
from ._tridiff import solve_diffusion as solve_diffusion
from ._tridiff import solver_methods as solver_methods

Border = Literal["replicate", "mirror", "zero", "periodic"]

def blur_methods() -> list[dict[str, Any]]: ...
def dof_methods() -> list[dict[str, Any]]: ...
def auto_blur_method(sigma: float, border: Border = "replicate",
                     max_error: float = 1e-3) -> str: ...
def blur(image: npt.ArrayLike, sigma: float, method: str = "auto", border: Border = "replicate",
         threads: int = 0, max_error: float = 1e-3) -> npt.NDArray[np.float32]: ...

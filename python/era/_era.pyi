"""Types of the native module era._era (crates/era-py). Axis order everywhere:
[output, input, frequency]. Thesis names: states = ns, hankel_factor = lh,
integrations = ni, zero_lines = nz, pad_to = ndpts, lowpass = (ford, Hzbreak),
time_domain = cord."""

import os
from typing import Any, Dict, List, Literal, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

PathLike = Union[str, "os.PathLike[str]"]
Quantity = Literal["acceleration", "velocity", "displacement"]
FloatArray = npt.NDArray[np.float64]
ComplexArray = npt.NDArray[np.complex128]

class FrfData:
    """FRFs G[i][j](f_k): values complex128 (q, p, L) at lines f_k = k·Δf from 0 Hz."""

    def __init__(
        self,
        frequency_hz: npt.ArrayLike,
        values: npt.ArrayLike,
        quantity: Quantity = "acceleration",
    ) -> None: ...
    @property
    def frequency_hz(self) -> FloatArray: ...
    @property
    def values(self) -> ComplexArray: ...
    @property
    def quantity(self) -> Quantity: ...
    @property
    def outputs(self) -> int: ...
    @property
    def inputs(self) -> int: ...
    @property
    def lines(self) -> int: ...
    @property
    def spacing_hz(self) -> float: ...
    def with_quantity(self, quantity: Quantity) -> "FrfData": ...
    def __eq__(self, other: object) -> bool: ...
    def __reduce__(self) -> Tuple[Any, Tuple[FloatArray, ComplexArray, str]]: ...

class Mode:
    """One complex pole pair: frequency |s|/2π, damping −Re s/|s|, shape Cφ,
    participation ψB; physical and indicators are None unless computed."""

    @property
    def frequency_hz(self) -> float: ...
    @property
    def damping_ratio(self) -> float: ...
    @property
    def eigenvalue(self) -> complex: ...
    @property
    def continuous_pole(self) -> complex: ...
    @property
    def shape(self) -> ComplexArray: ...
    @property
    def participation(self) -> ComplexArray: ...
    @property
    def physical(self) -> Optional[bool]: ...
    @property
    def indicators(self) -> Optional[Dict[str, Any]]: ...
    @property
    def frequency_std_hz(self) -> Optional[float]: ...
    @property
    def damping_ratio_std(self) -> Optional[float]: ...

class Identification:
    """The model (A, B, C, D), its Hankel singular values, modes and fit."""

    @property
    def a(self) -> FloatArray: ...
    @property
    def b(self) -> FloatArray: ...
    @property
    def c(self) -> FloatArray: ...
    @property
    def d(self) -> FloatArray: ...
    @property
    def sample_time_s(self) -> float: ...
    @property
    def time_domain(self) -> Literal["discrete", "continuous"]: ...
    @property
    def states(self) -> int: ...
    @property
    def singular_values(self) -> FloatArray: ...
    @property
    def frequency_hz(self) -> FloatArray: ...
    @property
    def damping_ratio(self) -> FloatArray: ...
    @property
    def eigenvalues(self) -> ComplexArray: ...
    @property
    def real_poles(self) -> FloatArray: ...
    @property
    def modes(self) -> List[Mode]: ...
    @property
    def hankel_size(self) -> Tuple[int, int]: ...
    @property
    def oma(self) -> Optional[Dict[str, Any]]: ...
    @property
    def warnings(self) -> List[str]: ...
    @property
    def parameters(self) -> Dict[str, Any]: ...
    @property
    def fit(self) -> Dict[str, Any]: ...
    @property
    def processed(self) -> FrfData: ...
    def response(self, frequency_hz: npt.ArrayLike) -> ComplexArray: ...
    def shapes_on(
        self,
        geometry: Union[PathLike, Dict[str, Any]],
        channels: Optional[Sequence[Tuple[int, Union[int, str]]]] = None,
    ) -> Dict[str, Any]: ...
    def to_json(self) -> str: ...
    def to_control(self) -> Any: ...

def read_frf(
    path: PathLike,
    quantity: Optional[Quantity] = None,
    outputs: Optional[int] = None,
    freq_variable: Optional[str] = None,
) -> FrfData: ...
def write_frf(path: PathLike, frf: FrfData, binary: bool = False) -> None: ...
def read_time(
    path: PathLike,
    variables: Sequence[str] = ...,
    datasets: Sequence[str] = ...,
    threads: Optional[int] = ...,
) -> Tuple[FloatArray, Optional[float], Optional[List[str]]]: ...
def read_geometry(path: PathLike) -> Dict[str, Any]: ...
def estimate_frf(
    data: npt.ArrayLike,
    sample_rate_hz: float,
    inputs: Sequence[int],
    outputs: Sequence[int],
    frame: int,
    window: Literal["hann", "rectangular", "flat-top"] = "hann",
    overlap: float = 0.5,
    estimator: Literal["h1", "h2", "hv"] = "h1",
    detrend: Literal["none", "mean", "linear"] = "mean",
    quantity: Quantity = "acceleration",
) -> Tuple[FrfData, FloatArray]: ...
def simulate_truth_model(noise: Optional[float] = None, seed: int = 1) -> FrfData: ...
def simulate_modal(
    outputs: int = 8,
    inputs: int = 8,
    modes: int = 40,
    fmin: float = 0.5,
    fmax: float = 14.0,
    damping: Tuple[float, float] = (0.005, 0.02),
    lines: int = 801,
    df: float = 0.025,
    quantity: Quantity = "acceleration",
    collocated: bool = False,
    noise: float = 0.0,
    seed: int = 1,
) -> FrfData: ...
def identify(
    frf: FrfData,
    states: Union[int, Literal["auto"]] = "auto",
    hankel_factor: int = 5,
    integrations: int = 0,
    zero_lines: int = 0,
    pad_to: int = 0,
    lowpass: Union[None, float, Tuple[int, float]] = None,
    time_domain: Optional[Literal["discrete", "continuous"]] = None,
    direct_term: Optional[Literal["zero", "markov0"]] = None,
    svd: Literal["auto", "dense", "matrix-free"] = "auto",
    era_dc: bool = False,
    refine: Optional[bool] = None,
    residuals: Literal["none", "lower", "upper", "both"] = "both",
    reciprocal: bool = False,
    weighting: Literal["pair-noise", "uniform"] = "pair-noise",
    max_iterations: int = 100,
    added_modes: bool = True,
    band: Optional[Tuple[float, float]] = None,
    preset: Literal["measured", "thesis"] = "measured",
    threads: Optional[int] = None,
) -> Identification: ...
def oma(
    data: Union[npt.ArrayLike, Sequence[npt.ArrayLike]],
    sample_rate_hz: float,
    outputs: Optional[Sequence[int]] = None,
    references: Optional[Sequence[int]] = None,
    method: Literal["ssi-cov", "next-era"] = "ssi-cov",
    states: Union[int, Literal["auto"]] = "auto",
    time_lags: Optional[int] = None,
    blocks: int = 6,
    threads: Optional[int] = None,
) -> Identification: ...
def friction_estimate(
    time_s: npt.ArrayLike, velocity: npt.ArrayLike, stiffness: float
) -> Dict[str, Any]: ...

"""SPH smoothing functions W(r, h) and their gradients, in 2D and 3D (MODEL.md section 0).

All have compact support of radius 2h. ``gradient(x_ij, r)`` returns grad_i W_ij for the
displacement x_ij = x_i - x_j; each function is written so that no division by r occurs,
which keeps coincident particles finite. ``second_derivative(r)`` is d^2W/dr^2 (the curvature
that bounds a stable particle-shifting step, physics/shifting.py). h and the dimension are
compile-time constants: an instance passed to a kernel as a template gets its own compiled code.
"""

import math

import taichi as ti


@ti.data_oriented
class SmoothingFunction:
    """Base class: ``value(r)`` [1/m^d], ``gradient(x_ij, r)`` [1/m^(d+1)] and
    ``second_derivative(r)`` [1/m^(d+2)]."""

    name = ""

    def __init__(self, smoothing_length: float, dim: int):
        if dim not in (2, 3):
            raise ValueError("dimension must be 2 or 3")
        self.h = float(smoothing_length)
        self.dim = dim
        self.support = 2.0 * self.h

    def describe(self) -> str:
        return f"{self.name} (h = {self.h:.4g} m, support 2h)"


@ti.data_oriented
class WendlandC2(SmoothingFunction):
    """W = sigma (1 + 2R)(2 - R)^4, R = r/h < 2 -- the formula printed as [M20].

    sigma = 7/(64 pi h^2) in 2D, 21/(256 pi h^3) in 3D. [M] calls it quartic "C4"; the
    polynomial is Wendland's C2 function.
    """

    name = "wendland_c2"

    def __init__(self, smoothing_length: float, dim: int):
        super().__init__(smoothing_length, dim)
        h = self.h
        self.sigma = 7.0 / (64.0 * math.pi * h**2) if dim == 2 else 21.0 / (256.0 * math.pi * h**3)

    @ti.func
    def value(self, r):
        R = r / self.h
        w = 0.0
        if R < 2.0:
            w = self.sigma * (1.0 + 2.0 * R) * (2.0 - R) ** 4
        return w

    @ti.func
    def gradient(self, x_ij, r):
        # dW/dR = -10 sigma R (2 - R)^3  =>  grad W = -10 sigma (2 - R)^3 x_ij / h^2
        R = r / self.h
        f = 0.0
        if R < 2.0:
            f = -10.0 * self.sigma * (2.0 - R) ** 3 / (self.h * self.h)
        return f * x_ij

    @ti.func
    def second_derivative(self, r):
        # d^2W/dR^2 = -10 sigma (2 - R)^2 (2 - 4R)
        R = r / self.h
        w2 = 0.0
        if R < 2.0:
            w2 = -10.0 * self.sigma * (2.0 - R) ** 2 * (2.0 - 4.0 * R) / (self.h * self.h)
        return w2


@ti.data_oriented
class WendlandC6(SmoothingFunction):
    """W = sigma (1 - q)^8 (32 q^3 + 25 q^2 + 8 q + 1), q = r/(2h) < 1 (Dehnen & Aly 2012; [P]).

    sigma = 78/(7 pi (2h)^2) in 2D, 1365/(64 pi (2h)^3) in 3D.
    """

    name = "wendland_c6"

    def __init__(self, smoothing_length: float, dim: int):
        super().__init__(smoothing_length, dim)
        H = 2.0 * self.h
        self.sigma = 78.0 / (7.0 * math.pi * H**2) if dim == 2 else 1365.0 / (64.0 * math.pi * H**3)

    @ti.func
    def value(self, r):
        q = r / self.support
        w = 0.0
        if q < 1.0:
            w = self.sigma * (1.0 - q) ** 8 * (((32.0 * q + 25.0) * q + 8.0) * q + 1.0)
        return w

    @ti.func
    def gradient(self, x_ij, r):
        # dW/dq = -22 sigma q (1 - q)^7 (16 q^2 + 7 q + 1), dq/dr = 1/(2h), q/r = 1/(2h)
        q = r / self.support
        f = 0.0
        if q < 1.0:
            f = -22.0 * self.sigma * (1.0 - q) ** 7 * ((16.0 * q + 7.0) * q + 1.0) / (self.support**2)
        return f * x_ij

    @ti.func
    def second_derivative(self, r):
        # d^2W/dq^2 = 22 sigma (1 - q)^6 (160 q^3 + 15 q^2 - 6 q - 1)
        q = r / self.support
        w2 = 0.0
        if q < 1.0:
            w2 = 22.0 * self.sigma * (1.0 - q) ** 6 * (((160.0 * q + 15.0) * q - 6.0) * q - 1.0) / (self.support**2)
        return w2


@ti.data_oriented
class CubicSpline(SmoothingFunction):
    """Monaghan & Lattanzio (1985) cubic spline [A10]:

    W = alpha (2/3 - R^2 + R^3/2) for R < 1, alpha (2 - R)^3/6 for 1 <= R < 2, with
    alpha = 15/(7 pi h^2) (2D), 3/(2 pi h^3) (3D). ([A10] misprints 2/3 as 1.5.)
    """

    name = "cubic_spline"

    def __init__(self, smoothing_length: float, dim: int):
        super().__init__(smoothing_length, dim)
        h = self.h
        self.alpha = 15.0 / (7.0 * math.pi * h**2) if dim == 2 else 3.0 / (2.0 * math.pi * h**3)

    @ti.func
    def value(self, r):
        R = r / self.h
        w = 0.0
        if R < 1.0:
            w = self.alpha * (2.0 / 3.0 - R * R + 0.5 * R**3)
        elif R < 2.0:
            w = self.alpha * (2.0 - R) ** 3 / 6.0
        return w

    @ti.func
    def gradient(self, x_ij, r):
        # grad W = alpha/h^2 * (dF/dR / R) * x_ij
        R = r / self.h
        f = 0.0
        if R < 1.0:
            f = -2.0 + 1.5 * R
        elif R < 2.0:
            f = -0.5 * (2.0 - R) ** 2 / R
        return (self.alpha / (self.h * self.h) * f) * x_ij

    @ti.func
    def second_derivative(self, r):
        # d^2F/dR^2 = -2 + 3R (R < 1), 2 - R (1 <= R < 2)
        R = r / self.h
        f2 = 0.0
        if R < 1.0:
            f2 = -2.0 + 3.0 * R
        elif R < 2.0:
            f2 = 2.0 - R
        return self.alpha / (self.h * self.h) * f2


SMOOTHING_FUNCTIONS = {cls.name: cls for cls in (WendlandC2, WendlandC6, CubicSpline)}


def make_smoothing(name: str, smoothing_length: float, dim: int) -> SmoothingFunction:
    return SMOOTHING_FUNCTIONS[name](smoothing_length, dim)

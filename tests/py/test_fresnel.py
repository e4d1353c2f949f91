"""Fresnel integrals and clothoid evaluation of `lissom-sim clothoid eval|fit` against independent
high-precision references (mpmath at 40 digits; scipy.special.fresnel as a second opinion).

The binary: env LISSOM_SIM, else build/bin/lissom-sim under the repository root (tests/py/conftest.py).

Accuracy claimed by firmware/path/clothoid.h: the normalised Fresnel integrals C(x), S(x) to 1e-12 relative in
double (measured about 1e-15); a general clothoid's displacement to 1e-12 relative, plus the rounding that
the phase theta(s) itself carries (about Phi * eps for a turning bound Phi).
"""
import math
import random

import mpmath as mp
import pytest
from scipy.special import fresnel as sp_fresnel

mp.mp.dps = 40


def eval_clothoid(sim, x0=0.0, y0=0.0, theta0=0.0, kappa0=0.0, c=0.0, s=0.0):
    return sim("clothoid", "eval", "--x0", repr(x0), "--y0", repr(y0), "--theta0", repr(theta0),
               "--kappa0", repr(kappa0), "--c", repr(c), "--s", repr(s), "--json")


def ref_displacement(theta0, kappa0, c, s):
    """int_0^s exp(i(theta0 + kappa0 t + c t^2/2)) dt with mpmath: closed forms through the Fresnel
    integrals (c != 0) or the circle / line (c == 0)."""
    th0, k0, c_, s_ = (mp.mpf(v) for v in (theta0, kappa0, c, s))
    if c == 0:
        if k0 == 0:
            return s_ * mp.cos(th0), s_ * mp.sin(th0)
        return (mp.sin(th0 + k0 * s_) - mp.sin(th0)) / k0, (mp.cos(th0) - mp.cos(th0 + k0 * s_)) / k0
    sg = 1 if c > 0 else -1
    ac = abs(c_)
    thv = th0 - k0 ** 2 / (2 * c_)
    q = mp.sqrt(mp.pi * ac)
    u0, u1 = sg * k0 / q, sg * (k0 + c_ * s_) / q
    dc = mp.fresnelc(u1) - mp.fresnelc(u0)
    ds = sg * (mp.fresnels(u1) - mp.fresnels(u0))
    z = mp.sqrt(mp.pi / ac) * mp.expj(thv) * (dc + 1j * ds)
    return z.real, z.imag


FRESNEL_X = [1e-6, 1e-3, 0.05, 0.3, 0.7, 1.0, 1.3, 1.59, 1.6, 1.61, 1.9, 2.5, 3.3, 4.4, 4.6, 5.0, 7.5, 10.0,
             31.4, 100.0, 1e3, 1e4, 12345.678]


@pytest.mark.parametrize("x", FRESNEL_X + [-v for v in (0.3, 1.7, 6.0)])
def test_normalised_fresnel(sim, x):
    """c = pi, kappa0 = theta0 = 0: x(s) = C(s), y(s) = S(s), the normalised Fresnel integrals."""
    r = eval_clothoid(sim, c=math.pi, s=x)
    # the reference for exactly the double the program received as c (math.pi, not pi):
    # int_0^x cos(c t^2/2) dt = sqrt(pi/c) C(x sqrt(c/pi)), likewise S
    cd = mp.mpf(math.pi)
    f = mp.sqrt(cd / mp.pi)
    Cr, Sr = mp.fresnelc(mp.mpf(x) * f) / f, mp.fresnels(mp.mpf(x) * f) / f
    assert abs(r["x"] - Cr) <= 1e-12 * abs(Cr), (x, r["x"], float(Cr))
    assert abs(r["y"] - Sr) <= 1e-12 * abs(Sr), (x, r["y"], float(Sr))
    assert r["theta"] == pytest.approx(math.pi * x * x / 2, rel=1e-15)
    assert r["kappa"] == pytest.approx(math.pi * x, rel=1e-15)


def test_fresnel_scipy_second_opinion(sim):
    """scipy.special.fresnel (Cephes) on a grid: agreement to scipy's own accuracy (~1e-15 relative)."""
    for x in [0.01 * k for k in range(1, 600, 7)]:
        S, C = sp_fresnel(x)
        r = eval_clothoid(sim, c=math.pi, s=x)
        assert r["x"] == pytest.approx(C, rel=5e-14, abs=1e-300)
        assert r["y"] == pytest.approx(S, rel=5e-14, abs=1e-300)


def random_cases(n, seed):
    rnd = random.Random(seed)
    cases = [(0.3, 0.2, 0.0, 7.0), (1.0, -3.0, 0.0, 40.0), (0.5, 0.1, 0.02, 10.0), (2.0, -0.5, 0.3, -4.0),
             (0.0, 0.0, 1.0, 100.0), (0.0, 0.0, -1.0, 100.0), (0.3, 17.0, 0.237, 16.4), (1.0, 4.0, -0.5, 30.0),
             (0.0, 1.0, 1e-9, 100.0), (0.0, 0.0, 1e-3, 300.0), (0.0, 0.5, -0.01, 100.0)]
    for _ in range(n):
        th0 = rnd.uniform(-4, 4)
        k0 = 0.0 if rnd.random() < 0.2 else rnd.choice((-1, 1)) * 10 ** rnd.uniform(-4, 0.7)
        c = 0.0 if rnd.random() < 0.15 else rnd.choice((-1, 1)) * 10 ** rnd.uniform(-6, 0.7)
        s = rnd.choice((-1, 1, 1, 1)) * 10 ** rnd.uniform(-3, 1.8)
        cases.append((th0, k0, c, s))
    return cases


@pytest.mark.parametrize("th0,k0,c,s", random_cases(60, 11))
def test_general_clothoid(sim, th0, k0, c, s):
    x0, y0 = 3.25, -1.5
    r = eval_clothoid(sim, x0, y0, th0, k0, c, s)
    X, Y = ref_displacement(th0, k0, c, s)
    phi = abs(k0 * s) + abs(c) * s * s / 2
    mag = float(mp.sqrt(X * X + Y * Y))
    tol = 1e-12 * mag + 2.3e-16 * (1 + phi) * abs(s)
    assert abs((r["x"] - x0) - float(X)) <= tol, (r, float(X), tol)
    assert abs((r["y"] - y0) - float(Y)) <= tol, (r, float(Y), tol)
    assert r["theta"] == pytest.approx(th0 + k0 * s + c * s * s / 2, rel=1e-14, abs=1e-14)
    assert r["kappa"] == pytest.approx(k0 + c * s, rel=1e-14, abs=1e-300)


FIT_CASES = [
    # x0, y0, theta0, kappa0, A, B, C
    (0, 0, 0, 0, 1, 0, -10),         # vertical line x = 10 straight ahead: the line itself, c = 0
    (0, 0, 0, 0, 0, 1, -10),         # horizontal line y = 10: turn by 90 deg
    (0, 0, 0.3, 0.05, 1, 1, -10),
    (0, 0, 1.5, 0, 1, 0, -5),
    (1, 1, 0, 0.2, 0, 1, -1.5),
    (0, 0, 0, -0.5, 1, 0.2, -3),
    (5, -2, 2.5, 0.01, -1, 0, -20),  # heading left towards x = -20
    (0, 0, 0.7, 0, 0, -3, 30),       # y = 10 written with B < 0
]


@pytest.mark.parametrize("x0,y0,th0,k0,A,B,C", FIT_CASES)
def test_fit_meets_line_at_right_angle(sim, x0, y0, th0, k0, A, B, C):
    r = sim("clothoid", "fit", "--x0", x0, "--y0", y0, "--theta0", th0, "--kappa0", k0,
            "--line", f"{A},{B},{C}", "--json")
    for key in ("c", "s", "x", "y", "theta", "kappa", "iterations"):
        assert key in r
    assert r["s"] > 0 and r["iterations"] >= 0
    # recompute the end independently with the returned c and s
    X, Y = ref_displacement(th0, k0, r["c"], r["s"])
    x, y = x0 + float(X), y0 + float(Y)
    h = math.hypot(A, B)
    assert abs(A * x + B * y + C) / h < 1e-10 * (1 + r["s"])
    th = th0 + k0 * r["s"] + r["c"] * r["s"] ** 2 / 2
    assert abs(math.cos(th) * B - math.sin(th) * A) / h < 1e-10  # tangent parallel to the normal
    assert r["x"] == pytest.approx(x, abs=1e-10 * (1 + r["s"]))
    assert r["y"] == pytest.approx(y, abs=1e-10 * (1 + r["s"]))
    assert r["theta"] == pytest.approx(th, abs=1e-12)
    assert r["kappa"] == pytest.approx(k0 + r["c"] * r["s"], abs=1e-12)

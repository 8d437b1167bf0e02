"""Physics and a small least-squares fitter for issue 32's held-out cases.

Python 3 standard library only.  Nothing here uses spindown's code or simulator.

Coast:  J dω/dt = -T(ω)  for ω > 0, with a friction torque T(ω) > 0 at ω = 0+ (so the shaft
stops in finite time and stays stopped).  Integrated with RK4 on a fine step; the stop is found
by linear interpolation inside the step where ω crosses 0.
"""
import math


def friction(cv=0.0, cc=0.0, cw=0.0, cs=None, ws=None):
    """T(ω) = cv·ω + cc + cw·ω² + (cs − cc)·exp(−(ω/ws)²)   (Stribeck term only if cs given)."""
    def T(w):
        t = cv * w + cc + cw * w * w
        if cs is not None:
            t += (cs - cc) * math.exp(-(w / ws) ** 2)
        return t
    return T


def coast(J, T, w0, h=1e-3, t_max=1e5):
    """Integrate the coast from ω0 at t = 0.  Returns (times, speeds, t_stop) on the fine grid
    (times[i] = i·h up to the stop, then the stop itself)."""
    ts, ws = [0.0], [w0]
    w, t = w0, 0.0

    def f(x):
        return -T(max(x, 0.0)) / J

    while t < t_max:
        k1 = f(w)
        k2 = f(w + 0.5 * h * k1)
        k3 = f(w + 0.5 * h * k2)
        k4 = f(w + h * k3)
        wn = w + h * (k1 + 2 * k2 + 2 * k3 + k4) / 6.0
        if wn <= 0.0:
            # stop inside this step: interpolate with the local slope (Coulomb-dominated there)
            frac = w / (w - wn)
            t_stop = t + frac * h
            ts.append(t_stop)
            ws.append(0.0)
            return ts, ws, t_stop
        t += h
        w = wn
        ts.append(t)
        ws.append(w)
    return ts, ws, None


class Coast:
    """A coast on a fine grid, evaluable at any time after the cut (0 after the stop)."""

    def __init__(self, J, T, w0, h=1e-3):
        self.h = h
        self.ts, self.ws, self.t_stop = coast(J, T, w0, h)

    def __call__(self, t):
        if t <= 0:
            return self.ws[0]
        if self.t_stop is not None and t >= self.t_stop:
            return 0.0
        i = int(t / self.h)
        if i + 1 >= len(self.ts):
            return self.ws[-1]
        t0, t1 = self.ts[i], self.ts[i + 1]
        w0, w1 = self.ws[i], self.ws[i + 1]
        return w0 + (w1 - w0) * (t - t0) / (t1 - t0)


def quantize(x, q):
    return q * round(x / q)


# ---------------------------------------------------------------------------------------------
# The lab's combined model (viscous + Coulomb), clamped at 0 after its own stop, fitted by
# Gauss-Newton/Levenberg-Marquardt with analytic derivatives.  Parameters p = (ω0, a, b) with
# a = c3/J, b = c4/J.  ω(t) = (ω0 + b/a)·e^(−a t) − b/a until ts = ln(1 + a ω0/b)/a, then 0.

def combined(t, p):
    w0, a, b = p
    r = b / a
    v = (w0 + r) * math.exp(-a * t) - r
    return v if v > 0 else 0.0


def combined_grad(t, p):
    w0, a, b = p
    r = b / a
    e = math.exp(-a * t)
    v = (w0 + r) * e - r
    if v <= 0:
        return (0.0, 0.0, 0.0)
    dw0 = e
    # d/da of (w0 + b/a) e^{-at} - b/a
    da = (-b / a / a) * e + (w0 + r) * (-t) * e + b / a / a
    db = e / a - 1.0 / a
    return (dw0, da, db)


def _solve3(A, y):
    # Gaussian elimination with partial pivoting, 3x3
    M = [row[:] + [y[i]] for i, row in enumerate(A)]
    n = 3
    for c in range(n):
        piv = max(range(c, n), key=lambda r: abs(M[r][c]))
        M[c], M[piv] = M[piv], M[c]
        for r in range(n):
            if r != c:
                f = M[r][c] / M[c][c]
                for k in range(c, n + 1):
                    M[r][k] -= f * M[c][k]
    return [M[i][n] / M[i][i] for i in range(n)]


def _inv3(A):
    cols = []
    for j in range(3):
        e = [1.0 if i == j else 0.0 for i in range(3)]
        cols.append(_solve3(A, e))
    return [[cols[j][i] for j in range(3)] for i in range(3)]


def fit_combined(ts, ys, p0, iters=200):
    """Least squares of the clamped combined model; returns (p, rss, JtJ)."""
    p = list(p0)
    lam = 1e-3

    def rss_of(pp):
        return sum((y - combined(t, pp)) ** 2 for t, y in zip(ts, ys))

    rss = rss_of(p)
    for _ in range(iters):
        A = [[0.0] * 3 for _ in range(3)]
        g = [0.0] * 3
        for t, y in zip(ts, ys):
            d = combined_grad(t, p)
            r = y - combined(t, p)
            for i in range(3):
                g[i] += d[i] * r
                for k in range(3):
                    A[i][k] += d[i] * d[k]
        improved = False
        for _try in range(30):
            Ad = [[A[i][k] * (1 + lam if i == k else 1) for k in range(3)] for i in range(3)]
            try:
                step = _solve3(Ad, g)
            except ZeroDivisionError:
                lam *= 10
                continue
            pn = [p[i] + step[i] for i in range(3)]
            if pn[1] <= 0 or pn[2] <= 0:
                lam *= 10
                continue
            rn = rss_of(pn)
            if rn < rss:
                rel = (rss - rn) / max(rss, 1e-300)
                p, rss = pn, rn
                lam = max(lam / 10, 1e-12)
                improved = True
                break
            lam *= 10
        if not improved or rel < 1e-14:
            break
    A = [[0.0] * 3 for _ in range(3)]
    for t in ts:
        d = combined_grad(t, p)
        for i in range(3):
            for k in range(3):
                A[i][k] += d[i] * d[k]
    return p, rss, A


def combined_se(A, sigma):
    """Standard errors of (ω0, a, b) for white noise σ: σ·sqrt(diag((JᵀJ)⁻¹))."""
    C = _inv3(A)
    return [sigma * math.sqrt(C[i][i]) for i in range(3)]


def stretch_stats(res, sigma, step, n=25):
    """Today's documented misfit rule (docs/cli.md) applied to residuals: stretches of n samples,
    a stretch mean's se = hypot(σ/√n, step/√12); returns (share with |z|>4, mean z²)."""
    se = math.hypot(sigma / math.sqrt(n), step / math.sqrt(12))
    zs = []
    for i in range(0, len(res) - n + 1, n):
        m = sum(res[i:i + n]) / n
        zs.append(m / se)
    if not zs:
        return 0.0, 0.0, 0
    share = sum(1 for z in zs if abs(z) > 4) / len(zs)
    mz2 = sum(z * z for z in zs) / len(zs)
    return share, mz2, len(zs)

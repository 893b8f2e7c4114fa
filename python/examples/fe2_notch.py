"""FE² in Python: a notched concrete strip in tension, then unloaded, with an RVE of
mesorve at every quadrature point (scikit-fem for the macro problem).

The macro mesh: a strip L x H of linear triangles (three quadrature points each, an RVE
at each) with a notch at the middle of its lower edge. The left edge is held in x (and
one corner in y), the right edge is pulled in x by u(t): up past the peak load, where the
strip localizes at the notch, then back to zero. Each increment is solved by Newton's
method with the RVEs' consistent tangents (`Points.update` over the whole mesh, trial),
then committed. The scene is the IMPL-EX host scene (scenes/paper_rve_host_implex.toml):
within an increment every RVE is linear, so the strip goes through its snap-back under
displacement control.

Writes OUT/force_displacement.png (the reaction against u), OUT/damage.png (D11 of each
RVE's tangent relative to the elastic one, at the peak and at the end) and
OUT/response.csv; exits non-zero if a check fails: Newton converges every increment, the
force peaks and then softens (the crack), the unloading goes back towards the origin
(secant unloading), and the softest RVEs are at the notch.

Usage: python fe2_notch.py [--out DIR] [--scene SCENE.toml] [--threads N]
"""

import argparse
import pathlib
import sys
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from skfem import Basis, BilinearForm, ElementTriP1, ElementVector, LinearForm, MeshTri  # noqa: E402
from skfem import asm, condense, solve  # noqa: E402

import mesorve  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]
L, H = 40.0, 20.0  # mm (the RVE is 10 mm)
NX, NY = 12, 6
NUP, NDOWN = 28, 10  # increments up, then down to u = 0


def notched_mesh():
    mesh = MeshTri.init_tensor(np.linspace(0, L, NX + 1), np.linspace(0, H, NY + 1))
    c = mesh.p[:, mesh.t].mean(axis=1)
    notch = np.nonzero((np.abs(c[0] - L / 2) < L / NX) & (c[1] < H / NY))[0]
    return mesh.remove_elements(notch)


def voigt(g):
    """[e_xx, e_yy, gamma_xy] of a displacement gradient g (2, 2, ...)."""
    return np.array([g[0, 0], g[1, 1], g[0, 1] + g[1, 0]])


@BilinearForm
def stiffness(u, v, w):
    eu, ev = voigt(u.grad), voigt(v.grad)
    return sum(ev[i] * w["D"][i, j] * eu[j] for i in range(3) for j in range(3))


@LinearForm
def internal(v, w):
    ev = voigt(v.grad)
    return sum(ev[i] * w["sig"][i] for i in range(3))


class Strip:
    def __init__(self, scene, threads):
        self.mesh = notched_mesh()
        self.basis = Basis(self.mesh, ElementVector(ElementTriP1()), intorder=1)
        self.nqp = self.basis.X.shape[-1]
        self.n = self.mesh.t.shape[1] * self.nqp
        self.model = mesorve.Model(scene)
        self.points = self.model.points(self.n, threads=threads)
        self.D0 = self.model.elastic_tangent()[0, 0]
        dofs = self.basis.get_dofs
        self.left_x = dofs(lambda x: np.isclose(x[0], 0)).nodal["u^1"]
        self.right_x = dofs(lambda x: np.isclose(x[0], L)).nodal["u^1"]
        # The lower left corner's y: a node, which get_dofs (facets) does not find.
        at_corner = np.isclose(self.mesh.p[0], 0) & np.isclose(self.mesh.p[1], 0)
        corner = self.basis.nodal_dofs[1, np.flatnonzero(at_corner)]
        if corner.size != 1:
            raise RuntimeError(f"expected one corner node at (0, 0), found {corner.size}")
        self.fixed = np.concatenate([self.left_x, self.right_x, corner])
        self.u = np.zeros(self.basis.N)

    def strains(self, u):
        g = self.basis.interpolate(u).grad  # (2, 2, nel, nqp)
        return voigt(g).reshape(3, -1).T

    def fields(self, sig, D):
        shape = (self.mesh.t.shape[1], self.nqp)
        return sig.T.reshape(3, *shape), D.transpose(1, 2, 0).reshape(3, 3, *shape)

    def increment(self, ux, dtime, tol=1e-8, max_iter=12):
        u = self.u.copy()
        u[self.right_x] = ux
        for it in range(1, max_iter + 1):
            sig, D = self.points.update(self.strains(u), dtime=dtime)
            s, d = self.fields(sig, D)
            f = asm(internal, self.basis, sig=s)
            K = asm(stiffness, self.basis, D=d)
            free = np.setdiff1d(np.arange(self.basis.N), self.fixed)
            r = np.linalg.norm(f[free])
            if r <= tol * max(np.abs(f[self.right_x]).sum(), 1e-12):
                self.points.commit()
                self.u = u
                return f[self.right_x].sum(), it, D
            u = u + solve(*condense(K, -f, D=self.fixed, x=np.zeros_like(u)))
        raise RuntimeError(f"Newton did not converge at u = {ux:.4g} (residual {r:.3g})")


def run(args):
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    strip = Strip(args.scene, args.threads)
    du = 6e-4  # mm per increment; the peak is near u = 7e-3
    up = [du * k for k in range(1, NUP + 1)]
    loads = up + [up[-1] * (1 - k / NDOWN) for k in range(1, NDOWN + 1)]
    rows, peak_D, t0 = [], None, time.perf_counter()
    for step, ux in enumerate(loads):
        force, its, D = strip.increment(ux, dtime=1.0)
        rows.append((step + 1, ux, force, its))
        if force >= max(r[2] for r in rows):
            peak_D = D[:, 0, 0] / strip.D0
    seconds = time.perf_counter() - t0
    end_D = D[:, 0, 0] / strip.D0
    data = np.array(rows)
    np.savetxt(out / "response.csv", data, delimiter=",", header="step,u,force,newton", comments="")
    pictures(strip, data, peak_D, end_D, out)
    return checks(strip, data, end_D, seconds)


def pictures(strip, data, peak_D, end_D, out):
    fig, ax = plt.subplots(figsize=(5, 3.5))
    ax.plot(data[:, 1], data[:, 2], "o-", ms=3)
    ax.set_xlabel("u (mm)")
    ax.set_ylabel("reaction force (N per mm thickness)")
    ax.set_title("notched strip, FE² with mesorve RVEs")
    fig.tight_layout()
    fig.savefig(out / "force_displacement.png", dpi=120)
    fig, axes = plt.subplots(2, 1, figsize=(6, 6))
    m = strip.mesh
    for ax, field, what in zip(axes, (peak_D, end_D), ("at the peak", "at the end")):
        field = field.reshape(m.t.shape[1], strip.nqp).mean(axis=1)
        tri = ax.tripcolor(m.p[0], m.p[1], m.t.T, facecolors=field, vmin=0, vmax=1, cmap="viridis")
        ax.set_aspect("equal")
        ax.set_title(f"D11 / D11 elastic {what}")
        fig.colorbar(tri, ax=ax)
    fig.tight_layout()
    fig.savefig(out / "damage.png", dpi=120)


def checks(strip, data, end_D, seconds):
    force = data[:, 2]
    k = int(np.argmax(force))
    ok = True

    def check(cond, what):
        nonlocal ok
        print(("   ok: " if cond else "   FAILED: ") + what)
        ok &= bool(cond)

    k = int(np.argmax(force[: NUP // 2 + 5]))  # the first peak
    check(0 < k and force[k + 2] < force[k], f"the force peaks (increment {k + 1}) and softens")
    secant = force[NUP - 1] / data[NUP - 1, 1]
    initial = force[0] / data[0, 1]
    check(secant < 0.6 * initial, f"secant stiffness at the end of tension {secant / initial:.2f} of the initial")
    down = slice(NUP, len(data) - 1)
    ratio = force[down] / data[down, 1]
    check(np.ptp(ratio) < 0.05 * secant and abs(force[-1]) < 1e-6 * force[k],
          "unloading: straight back to the origin (secant unloading of the ITZ)")
    c = strip.basis.mapping.F(strip.basis.X).reshape(2, -1)  # the RVEs' positions
    softest = np.argsort(end_D)[:3]
    check(np.all(np.abs(c[0, softest] - L / 2) < L / 4), "the softest RVEs are at the notch")
    print(f"fe2_notch: {strip.n} RVEs, {len(data)} increments, {int(data[:, 3].sum())} Newton "
          f"iterations, peak {force[k]:.4g} N/mm at u = {data[k, 1]:.3g} mm, {seconds:.1f} s")
    return ok


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default="fe2_notch_out")
    p.add_argument("--scene", default=str(ROOT / "scenes" / "paper_rve_host_implex.toml"))
    p.add_argument("--threads", type=int, default=0)
    return 0 if run(p.parse_args()) else 1


if __name__ == "__main__":
    sys.exit(main())

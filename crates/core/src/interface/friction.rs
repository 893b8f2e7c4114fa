//! Coulomb friction on a closed crack: the return mapping of the shear traction of the
//! damaged part of a closed interface point, with its consistent tangent. A building block
//! of the laws' friction (`docs/fracture.md`, "Friction: the design for the next step"):
//! no law calls it yet.
//!
//! With the normal traction `t_n <= 0` of the closed point (`t_n = k_p delta_n`), the
//! shear stiffness `k` of the stick state and the slip `s` (history), the trial shear
//! traction is `t* = k (delta_s - s)` and (Alfano & Sacco 2006, the frictional part)
//! ```text
//! |t*| <= mu |t_n|:  t_f = t*,                   s unchanged      (stick)
//! |t*| >  mu |t_n|:  t_f = mu |t_n| sign(t*),    s = delta_s - t_f / k   (slip)
//! ```
//! Tangent: stick `d t_f / d delta_s = k`, `d t_f / d delta_n = 0`; slip `d t_f / d delta_s
//! = 0`, `d t_f / d delta_n = -mu sign(t*) d t_n / d delta_n` (`|t_n| = -t_n`). Sliding, the
//! shear depends on the normal jump while the normal traction does not depend on the
//! shear jump: the tangent of a sliding point is not symmetric.
//!
//! OOFEM's `IntMatCoulombContact` maps the same way, written with the shear stress shift
//! `k s` instead of the slip (its tractions equal these along any path, checked below);
//! its stiffness matrix is the elastic `k I` in stick and slip alike, not the consistent
//! tangent, so a host's Newton converges linearly with it where this one's is quadratic.

/// Coulomb's law with a stick stiffness.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coulomb {
    /// The friction coefficient `mu` (>= 0).
    pub coefficient: f64,
    /// The shear stiffness `k` of the stick state, per unit area.
    pub stiffness: f64,
}

/// The frictional shear of a closed point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrictionPoint {
    /// The shear traction `t_f`.
    pub traction: f64,
    /// `d t_f / d delta_s`.
    pub d_shear: f64,
    /// `d t_f / d delta_n`.
    pub d_normal: f64,
    /// The trial slip `s`.
    pub slip: f64,
    /// Whether the point slides.
    pub sliding: bool,
}

impl Coulomb {
    /// The frictional shear at the shear jump `shear_jump` from the committed `slip`, with
    /// the normal traction `normal` (compression negative; tension gives no friction) and
    /// its derivative `d_normal` with respect to the normal jump.
    pub fn respond(&self, slip: f64, shear_jump: f64, normal: f64, d_normal: f64) -> FrictionPoint {
        let trial = self.stiffness * (shear_jump - slip);
        let limit = self.coefficient * (-normal).max(0.0);
        if trial.abs() <= limit {
            return FrictionPoint {
                traction: trial,
                d_shear: self.stiffness,
                d_normal: 0.0,
                slip,
                sliding: false,
            };
        }
        let sign = trial.signum();
        let traction = sign * limit;
        FrictionPoint {
            traction,
            d_shear: 0.0,
            d_normal: if normal < 0.0 {
                -self.coefficient * sign * d_normal
            } else {
                0.0
            },
            slip: shear_jump - traction / self.stiffness,
            sliding: true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LAW: Coulomb = Coulomb {
        coefficient: 0.6,
        stiffness: 1e4,
    };
    /// The normal penalty of the tests: `t_n = KP delta_n`.
    const KP: f64 = 2e4;

    fn at(slip: f64, ds: f64, dn: f64) -> FrictionPoint {
        LAW.respond(slip, ds, KP * dn, KP)
    }

    /// Sticks until `|t| = mu |t_n|`, then slides at that traction, its slip the jump
    /// beyond the stick one; no friction in tension.
    #[test]
    fn sticks_until_the_coulomb_limit_then_slides() {
        let dn = -1e-3; // t_n = -20: the limit is 12
        let limit = LAW.coefficient * KP * 1e-3;
        let stuck = at(0.0, 0.5 * limit / LAW.stiffness, dn);
        assert!(!stuck.sliding);
        assert!((stuck.traction - 0.5 * limit).abs() <= 1e-12 * limit);
        let ds = 3.0 * limit / LAW.stiffness;
        let slides = at(0.0, ds, dn);
        assert!(slides.sliding);
        assert!((slides.traction - limit).abs() <= 1e-12 * limit);
        assert!((slides.slip - (ds - limit / LAW.stiffness)).abs() <= 1e-15);
        let back = at(0.0, -ds, dn);
        assert!((back.traction + limit).abs() <= 1e-12 * limit);
        let open = at(0.0, ds, 1e-3);
        assert_eq!((open.traction, open.d_normal), (0.0, 0.0));
    }

    /// The tangent against central differences, stick and slip in both directions.
    #[test]
    fn tangent_matches_central_differences() {
        let h = 1e-9;
        for (slip, ds, dn) in [
            (0.0, 2e-4, -1e-3),
            (1e-4, 2e-4, -1e-3),
            (0.0, 5e-3, -1e-3),
            (2e-3, -4e-3, -2e-3),
        ] {
            let p = at(slip, ds, dn);
            let fd_s = (at(slip, ds + h, dn).traction - at(slip, ds - h, dn).traction) / (2.0 * h);
            let fd_n = (at(slip, ds, dn + h).traction - at(slip, ds, dn - h).traction) / (2.0 * h);
            let scale = LAW.stiffness.max(LAW.coefficient * KP);
            assert!(
                (p.d_shear - fd_s).abs() <= 1e-6 * scale,
                "{p:?}: d/ds {fd_s}"
            );
            assert!(
                (p.d_normal - fd_n).abs() <= 1e-6 * scale,
                "{p:?}: d/dn {fd_n}"
            );
        }
    }

    /// OOFEM's `IntMatCoulombContact` (2D, no clearance): the trial shear stress
    /// `k delta_s - shift`, scaled back to `mu |t_n|`, the shift updated to `k delta_s - t`.
    /// Written from its description, as a second implementation: along a random closed
    /// path its shear tractions equal `Coulomb::respond`'s to round-off.
    #[test]
    fn tractions_equal_oofems_return_mapping() {
        let (k, mu) = (LAW.stiffness, LAW.coefficient);
        let (mut slip, mut shift) = (0.0, 0.0);
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut largest = 0.0f64;
        for _ in 0..2000 {
            let (ds, dn) = (4e-3 * (next() - 0.5), -2e-3 * next());
            let ours = at(slip, ds, dn);
            slip = ours.slip;
            let normal = KP * dn;
            let mut shear = k * ds - shift;
            let limit = (normal.abs()) * mu;
            if shear.abs() > limit {
                shear *= limit / (shear.abs() + 1e-15);
            }
            shift = k * ds - shear;
            largest = largest.max((ours.traction - shear).abs());
        }
        assert!(largest <= 1e-12 * LAW.coefficient * KP * 2e-3, "{largest}");
    }

    /// A shear cycle of amplitude `a` at a constant normal traction dissipates the loop of
    /// an elastic-perfectly plastic spring: `4 tau (a - tau / k)` per cycle after the first
    /// loading, with `tau = mu |t_n|`; the trapezoid rule is exact here (the stick spans
    /// fall on whole steps, the traction is linear between them).
    #[test]
    fn a_shear_cycle_dissipates_the_closed_form_loop() {
        let dn = -1e-3;
        let tau = LAW.coefficient * KP * 1e-3;
        let a = 10.0 * tau / LAW.stiffness;
        let n = 20000;
        // 0 -> a, then a -> -a -> a (one closed cycle), measured on the closed cycle.
        let mut path: Vec<f64> = (0..=n).map(|k| a * k as f64 / n as f64).collect();
        path.extend((1..=2 * n).map(|k| a - 2.0 * a * k as f64 / (2 * n) as f64));
        path.extend((1..=2 * n).map(|k| -a + 2.0 * a * k as f64 / (2 * n) as f64));
        let (mut slip, mut previous, mut work) = (0.0, (0.0, 0.0), 0.0);
        for (k, &ds) in path.iter().enumerate() {
            let p = at(slip, ds, dn);
            slip = p.slip;
            if k > n {
                work += 0.5 * (p.traction + previous.1) * (ds - previous.0);
            }
            previous = (ds, p.traction);
        }
        let exact = 4.0 * tau * (a - tau / LAW.stiffness);
        println!(
            "loop {work} against {exact}: {:.1e}",
            (work - exact).abs() / exact
        );
        assert!(
            (work - exact).abs() <= 1e-6 * exact,
            "loop {work} against {exact}"
        );
    }
}

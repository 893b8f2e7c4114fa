//! The UMAT's inspection mirrors: values a host can plot per integration point (cgx,
//! ParaView), written after the RVE state in `STATEV` mode and from `STATEV(1)` in table
//! mode, as many as `NSTATV` leaves room for. The library never reads them.
//!
//! | mirror | value |
//! |---|---|
//! | 1 | the point's id in the process (1, 2, ... in creation order; for a host without `PNEWDT` the id of the thread's RVE instance that answered, which identifies no point) |
//! | 2 | RVE Newton iterations of the answer |
//! | 3 | RVE sub-steps of the answer |
//! | 4 | the RVE's damage `D` in `[0, 1)`, below |
//! | 5 | the largest ITZ opening reached, `max_q delta_max,q` (length units) |
//!
//! **Damage.** The ITZ-length-weighted mean of the interface law's point damage, the
//! secant stiffness lost at each ITZ quadrature point `q` (for the paper's law, eqs. 23-24:
//! `d_q = 1 - k(delta_max,q) / k(0) = 1 - exp(-delta_max,q / delta_c)`):
//!
//! ```text
//! D = sum_e sum_q (w_q / 2) l_e d_q  /  sum_e l_e
//! ```
//!
//! with `l_e` the length of interface element `e` and `w_q` the weights of its rule on
//! `[-1, 1]`. `D = 0` for a virgin RVE; `D -> 1` only when every ITZ point has opened far
//! beyond `delta_c`. It measures the ITZ alone: the paste and aggregates stay elastic, so
//! `D = 1` does not mean that the RVE carries nothing.
//!
//! **Opening.** `delta_max` is the largest effective opening a point has reached (eq. 20,
//! `sqrt(beta^2 delta_s^2 + delta_n^2)` while open; the normal jump for a crack opened
//! in mode I). It is history: a crack that closes under compression keeps its value. (The
//! present jump is not formed by the updates that answer without a solve, so it is not
//! mirrored.) Both are taken from the history of the state the call leaves for the host
//! ([`Instance::trial_history`]), so they are those of the converged state once the host
//! keeps the increment. A law without a characteristic opening (`linear_itz`), or a scene
//! without interfaces, gives 0 for both.

use crate::model::{Instance, Model};
use mesorve_core::assembly::InterfaceLaws;
use mesorve_core::element::InterfaceGeometry;

/// Mirrors written at most.
pub const MIRRORS: usize = 5;

/// Damage and largest opening of an RVE state (see the module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RveMeasures {
    /// ITZ-length-weighted mean point damage, in `[0, 1)`.
    pub damage: f64,
    /// Largest `delta_max` over the ITZ points (length units).
    pub max_opening: f64,
}

impl RveMeasures {
    /// The measures of the interface history `history` (`State::history` layout: element
    /// by element, point by point) of a state of `model`. Allocates nothing.
    pub fn of(model: &Model, history: &[f64]) -> RveMeasures {
        let disc = &model.disc;
        let Some(laws) = disc.law.as_ref() else {
            return RveMeasures::default();
        };
        measures(laws, disc.quadrature.rule(), &disc.interfaces, history)
    }
}

fn measures(
    laws: &InterfaceLaws,
    rule: &[(f64, f64)],
    interfaces: &[InterfaceGeometry],
    history: &[f64],
) -> RveMeasures {
    let hl = laws.history_len();
    let per_element = rule.len() * hl;
    let (mut weighted, mut length, mut max_opening) = (0.0, 0.0, 0.0f64);
    for (e, geometry) in interfaces.iter().enumerate() {
        let h = &history[e * per_element..(e + 1) * per_element];
        let law = laws.of(e);
        for (p, &(_, w)) in rule.iter().enumerate() {
            let Some((damage, opening)) =
                law.history_measures(&h[p * hl..(p + 1) * hl], geometry.length)
            else {
                return RveMeasures::default();
            };
            weighted += 0.5 * w * geometry.length * damage;
            max_opening = max_opening.max(opening);
        }
        length += geometry.length;
    }
    RveMeasures {
        damage: if length > 0.0 { weighted / length } else { 0.0 },
        max_opening,
    }
}

/// The mirrors of a point: its id and the answer's iterations and sub-steps, then the
/// measures of the history `instance` leaves for the host, computed only when `room` (the
/// entries the host has for mirrors) reaches them (a pass over the ITZ points).
pub fn mirrors(
    id: u64,
    iterations: u32,
    substeps: u32,
    instance: &Instance,
    room: usize,
) -> [f64; MIRRORS] {
    mirrors_of(
        id,
        iterations,
        substeps,
        (instance.model(), instance.trial_history()),
        room,
    )
}

/// [`mirrors`] of a model's interface `history` (a shared answer's written state).
pub fn mirrors_of(
    id: u64,
    iterations: u32,
    substeps: u32,
    (model, history): (&crate::Model, &[f64]),
    room: usize,
) -> [f64; MIRRORS] {
    let m = if room > 3 {
        RveMeasures::of(model, history)
    } else {
        RveMeasures::default()
    };
    [
        id as f64,
        f64::from(iterations),
        f64::from(substeps),
        m.damage,
        m.max_opening,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::cache;
    use crate::scene::DEFAULT_SCENE_TOML;

    /// A uniform history gives its point damage and opening exactly; one opened point
    /// moves the mean by its share of the ITZ length and sets the largest opening.
    #[test]
    fn damage_is_the_length_weighted_mean_and_opening_the_largest() {
        let model = cache::model_for_text(DEFAULT_SCENE_TOML, None).unwrap();
        let disc = &model.disc;
        let n = disc.history_len();
        assert!(n > 0);
        assert_eq!(
            RveMeasures::of(&model, &vec![0.0; n]),
            RveMeasures::default()
        );
        let delta_c = 2e-4; // the paper's, in scenes/paper_rve.toml
        let uniform = RveMeasures::of(&model, &vec![delta_c; n]);
        let d = 1.0 - (-1.0f64).exp();
        assert!((uniform.damage - d).abs() < 1e-14 * d, "{uniform:?}");
        assert_eq!(uniform.max_opening, delta_c);
        // One quadrature point of the first element opened to 10 delta_c.
        let rule = disc.quadrature.rule();
        let mut h = vec![0.0; n];
        h[0] = 10.0 * delta_c;
        let one = RveMeasures::of(&model, &h);
        let total: f64 = disc.interfaces.iter().map(|g| g.length).sum();
        let share = 0.5 * rule[0].1 * disc.interfaces[0].length / total;
        let want = share * (1.0 - (-10.0f64).exp());
        assert!(
            (one.damage - want).abs() < 1e-14,
            "{} vs {want}",
            one.damage
        );
        assert_eq!(one.max_opening, 10.0 * delta_c);
        assert!(one.damage > 0.0 && one.damage < 1.0);
        // The history-only shortcut equals the law's full measures.
        let law = disc.law.as_ref().unwrap().itz();
        for x in [0.0, 0.3, 1.0, 7.5] {
            let h = [x * delta_c];
            let full = law.measures(&h, [1e-5, -2e-5], 0.5).unwrap();
            let quick = law.history_measures(&h, 0.5).unwrap();
            assert!(
                (quick.0 - full.damage).abs() <= 1e-15,
                "{x}: {quick:?} {full:?}"
            );
            assert_eq!(quick.1, full.max_opening);
        }
    }
}

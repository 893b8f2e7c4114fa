//! One point of a fully open crack with Coulomb friction (`interface::Frictional` over the
//! paste's `CrackLaw`) along a path of local jumps: for comparing the law with another
//! code (`studies/friction-akantu`).
//!
//! ```text
//! cargo run --release --example friction_path -- MU K KP < jumps.txt
//! ```
//! reads lines `delta_s delta_n`, commits each, and prints `delta_s,delta_n,t_s,t_n,slip`.
//! `K` is the stick stiffness of the damaged part, `KP` the contact penalty. The crack is
//! fully open from the start (damage 1 to `RESIDUAL`), so its own shear on the secant is
//! `RESIDUAL K delta_s` and the stick stiffness is `K` to that fraction.

use std::io::BufRead;
use std::sync::Arc;

use mesorve_core::interface::{
    ContactShear, CrackLaw, Frictional, InterfaceLaw, TangentKind, RESIDUAL,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse::<f64>())
        .collect::<Result<_, _>>()?;
    let [mu, k, kp] = args[..] else {
        return Err("usage: friction_path MU K KP < jumps".into());
    };
    let crack = CrackLaw {
        strength: 1.0,
        fracture_energy: 1e-3,
        stiffness: k / (1.0 - RESIDUAL),
        beta: 1.0,
        penalty: kp,
        contact: true,
        contact_shear: ContactShear::Cohesive,
    };
    let law = Frictional::new(Arc::new(crack), mu, "mu")?;
    let mut history = vec![1e3 * crack.critical_opening(), 0.0];
    let mut trial = history.clone();
    println!("delta_s,delta_n,t_s,t_n,slip");
    for line in std::io::stdin().lock().lines() {
        let line = line?;
        let values: Vec<f64> = line
            .split_whitespace()
            .map(str::parse)
            .collect::<Result<_, _>>()?;
        let [ds, dn] = values[..] else {
            continue;
        };
        let p = law.respond(&history, &mut trial, [ds, dn], 1.0, TangentKind::Consistent);
        history.copy_from_slice(&trial);
        println!(
            "{ds:e},{dn:e},{:e},{:e},{:e}",
            p.traction.x, p.traction.y, history[1]
        );
    }
    Ok(())
}

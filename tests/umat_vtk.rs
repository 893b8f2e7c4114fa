//! `MESORVE_UMAT_VTK` (`rve::host::VtkDump`): the UMAT writes the RVE fields of chosen
//! points as VTK, through the safe UMAT API.
//!
//! What is asserted: a chosen point driven through uniaxial tension past the peak, in
//! `STATEV` mode and in table mode, gets one `.vtu` per increment and a `.pvd` listing them
//! in time order; each file holds that point's answer: the macro strain recovered from the
//! corner displacements is the call's `STRAN + DSTRAN`, the area average of the cell
//! stresses is the `STRESS` returned, and the ITZ-length-weighted mean of the per-element
//! damage is the damage mirror in `STATEV`; damage grows past the stress peak. An earlier
//! iteration of an increment is overwritten, a repeated call writes nothing, a point not
//! chosen gets no file, and the answers are those of a table without the switch, bit for
//! bit. With IMPL-EX the increments that reuse their step's factorization get no file and
//! are counted, the others hold their answer. Bad values give one message naming the
//! variable and the value; a directory that goes away makes writes fail without failing a
//! call.

mod common;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use rve::host::{SearchPath, Umat, UmatOutputs, VtkDump, VtkSpec, UMAT_VTK_VAR};
use rve::model::cache;

const INCREMENTS: usize = 12;
const END: f64 = 3e-4;

fn umat(dump: Option<VtkDump>) -> Umat {
    Umat::new(SearchPath::new([common::repo("scenes")])).with_vtk(dump)
}

fn statev_len() -> usize {
    let file = common::repo("scenes/paper_rve.toml");
    cache::model_for_file(&file).unwrap().statev_len()
}

fn temp(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mesorve-umat-vtk-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// One call of point `(noel, 1)` in increment `k` (1-based) at total strain `eps_xx`;
/// returns STRESS and the STATEV written.
fn call(table: &Umat, noel: i32, k: usize, eps: f64, statev: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let start = END * (k - 1) as f64 / INCREMENTS as f64;
    call_from(table, "paper_rve", noel, k, [start, eps], statev)
}

/// [`call`] of material `cmname` from `strain[0]` to `strain[1]`.
fn call_from(
    table: &Umat,
    cmname: &str,
    noel: i32,
    k: usize,
    strain: [f64; 2],
    statev: &[f64],
) -> (Vec<f64>, Vec<f64>) {
    let (stran, dstran) = ([strain[0], 0.0, 0.0], [strain[1] - strain[0], 0.0, 0.0]);
    let c = common::cycle_call(cmname, &[], &stran, &dstran, noel, k - 1);
    let (mut stress, mut ddsdde, mut pnewdt) = (vec![0.0; 3], vec![0.0; 9], -1.0);
    let mut statev = statev.to_vec();
    let mut out = UmatOutputs {
        stress: &mut stress,
        ddsdde: &mut ddsdde,
        statev: &mut statev,
        pnewdt: &mut pnewdt,
    };
    table.call(&c, &mut out).unwrap();
    (stress, statev)
}

/// Drives point `noel` through the increments as CalculiX does: an iteration at 90 % of
/// the increment's strain, then two calls at its end (stress, tangent), `STATEV` of the
/// increment's start at each. Returns per increment the end strain, STRESS and the damage
/// mirror.
fn drive(table: &Umat, noel: i32, nstatv: usize) -> Vec<(f64, Vec<f64>, f64)> {
    let damage_at = if nstatv > 5 { statev_len() + 3 } else { 3 };
    let mut kept = vec![0.0; nstatv];
    let mut out = Vec::new();
    for k in 1..=INCREMENTS {
        let (start, end) = (END * (k - 1) as f64, END * k as f64);
        let (start, end) = (start / INCREMENTS as f64, end / INCREMENTS as f64);
        call(table, noel, k, start + 0.9 * (end - start), &kept);
        let (stress, statev) = call(table, noel, k, end, &kept);
        let (again, _) = call(table, noel, k, end, &kept);
        assert_eq!(bits(&stress), bits(&again));
        out.push((end, stress, statev[damage_at]));
        kept = statev;
    }
    out
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// The `DataArray`s of a `.vtu` written by `rve::io::write_vtu_fields`, by name (`Points`
/// for the unnamed coordinates).
fn read_vtu(path: &Path) -> HashMap<String, Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    assert!(
        text.trim_end().ends_with("</VTKFile>"),
        "{}",
        path.display()
    );
    let mut arrays = HashMap::new();
    for block in text.split("<DataArray").skip(1) {
        let (head, rest) = block.split_once('>').unwrap();
        let name = head
            .split("Name=\"")
            .nth(1)
            .map_or("Points", |s| s.split('"').next().unwrap());
        let body = rest.split("</DataArray>").next().unwrap();
        let values = body
            .split_whitespace()
            .map(|v| v.parse::<f64>().unwrap())
            .collect();
        arrays.insert(name.to_string(), values);
    }
    arrays
}

/// What a file says of its point: the macro strain from the corner displacements (the
/// cell is periodic), the area-averaged stress, and the ITZ-length-weighted mean damage.
fn file_measures(a: &HashMap<String, Vec<f64>>) -> ([f64; 3], [f64; 3], f64) {
    let p: Vec<[f64; 2]> = a["Points"].chunks(3).map(|c| [c[0], c[1]]).collect();
    let u: Vec<[f64; 2]> = a["displacement"].chunks(3).map(|c| [c[0], c[1]]).collect();
    let (lo, hi) = p
        .iter()
        .fold(([f64::MAX; 2], [f64::MIN; 2]), |(lo, hi), q| {
            (
                [lo[0].min(q[0]), lo[1].min(q[1])],
                [hi[0].max(q[0]), hi[1].max(q[1])],
            )
        });
    let corner = |x: f64, y: f64| p.iter().position(|q| *q == [x, y]).unwrap();
    let (c0, cx, cy) = (
        corner(lo[0], lo[1]),
        corner(hi[0], lo[1]),
        corner(lo[0], hi[1]),
    );
    let (lx, ly) = (hi[0] - lo[0], hi[1] - lo[1]);
    let strain = [
        (u[cx][0] - u[c0][0]) / lx,
        (u[cy][1] - u[c0][1]) / ly,
        (u[cy][0] - u[c0][0]) / ly + (u[cx][1] - u[c0][1]) / lx,
    ];
    let offsets = &a["offsets"];
    let conn = &a["connectivity"];
    let (mut stress, mut damage, mut length) = ([0.0; 3], 0.0, 0.0);
    let mut from = 0;
    for (cell, &to) in offsets.iter().enumerate() {
        let n: Vec<usize> = conn[from..to as usize]
            .iter()
            .map(|&v| v as usize)
            .collect();
        from = to as usize;
        if n.len() == 3 {
            let (a0, b, c) = (p[n[0]], p[n[1]], p[n[2]]);
            let area =
                0.5 * ((b[0] - a0[0]) * (c[1] - a0[1]) - (c[0] - a0[0]) * (b[1] - a0[1])).abs();
            for (k, s) in stress.iter_mut().enumerate() {
                *s += area * a["stress"][3 * cell + k] / (lx * ly);
            }
        } else {
            let l = (p[n[1]][0] - p[n[0]][0]).hypot(p[n[1]][1] - p[n[0]][1]);
            damage += l * a["damage"][cell];
            length += l;
        }
    }
    (strain, stress, damage / length)
}

/// Checks the files of point `noel` against what `drive` returned.
fn check_files(dir: &Path, noel: i32, answers: &[(f64, Vec<f64>, f64)]) {
    let pvd = std::fs::read_to_string(dir.join(VtkDump::index_name(noel, 1))).unwrap();
    let listed: Vec<&str> = pvd
        .split("file=\"")
        .skip(1)
        .map(|s| s.split('"').next().unwrap())
        .collect();
    let expected: Vec<String> = (1..=INCREMENTS)
        .map(|k| VtkDump::file_name(noel, 1, 1, k as i32))
        .collect();
    assert_eq!(listed, expected, "{pvd}");
    let mut previous_damage = 0.0;
    for (k, (eps, stress, mirror)) in answers.iter().enumerate() {
        let arrays = read_vtu(&dir.join(&expected[k]));
        let (strain, avg, damage) = file_measures(&arrays);
        let strain_err = (strain[0] - eps)
            .abs()
            .max(strain[1].abs())
            .max(strain[2].abs());
        assert!(
            strain_err <= 1e-11 * END,
            "increment {}: strain {strain:?}, eps_xx {eps}",
            k + 1
        );
        let scale = stress.iter().fold(0.0f64, |m, s| m.max(s.abs()));
        let stress_err = (0..3).fold(0.0f64, |m, i| m.max((avg[i] - stress[i]).abs())) / scale;
        assert!(
            stress_err <= 1e-9,
            "increment {}: {avg:?} against {stress:?}",
            k + 1
        );
        assert!(
            (damage - mirror).abs() <= 1e-12,
            "increment {}: {damage} against {mirror}",
            k + 1
        );
        assert!(damage >= previous_damage, "damage is history");
        previous_damage = damage;
    }
}

/// The peak of `s_xx` is an interior increment, and damage grows after it.
fn check_peak(answers: &[(f64, Vec<f64>, f64)]) {
    let peak = (0..answers.len())
        .max_by(|&a, &b| answers[a].1[0].total_cmp(&answers[b].1[0]))
        .unwrap();
    assert!(peak + 1 < answers.len(), "no peak before {END}");
    assert!(answers[answers.len() - 1].1[0] < answers[peak].1[0]);
    assert!(
        answers[answers.len() - 1].2 > answers[peak].2,
        "no damage after the peak"
    );
}

#[test]
fn chosen_points_get_their_rve_fields_per_increment() {
    let dir = temp("points");
    let spec = format!("{}:1.1,2.1", dir.display());
    let dump = VtkDump::from_value(&spec).unwrap();
    assert_eq!(dump.spec().points, vec![(1, 1), (2, 1)]);
    let table = umat(Some(dump));
    let nstatv = statev_len() + 5;
    let statev_mode = drive(&table, 1, nstatv);
    let table_mode = drive(&table, 2, 5);
    let not_chosen = drive(&table, 3, nstatv);
    for (noel, n, answers) in [
        (1, nstatv, &statev_mode),
        (2, 5, &table_mode),
        (3, nstatv, &not_chosen),
    ] {
        let reference = drive(&umat(None), noel, n);
        let b = |a: &[(f64, Vec<f64>, f64)]| a.iter().map(|x| bits(&x.1)).collect::<Vec<_>>();
        assert_eq!(b(answers), b(&reference), "the switch changed an answer");
    }
    check_files(&dir, 1, &statev_mode);
    check_files(&dir, 2, &table_mode);
    check_peak(&statev_mode);
    // Two iterations per increment and point are written (the repeat is not).
    let vtk = table.vtk().unwrap();
    assert_eq!(vtk.written(), 2 * 2 * INCREMENTS as u64);
    assert_eq!(vtk.failures(), 0);
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        names
            .iter()
            .all(|n| n.starts_with("e1_") || n.starts_with("e2_")),
        "{names:?}"
    );
    assert_eq!(names.len(), 2 * (INCREMENTS + 1), "{names:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_values_are_one_message_and_no_switch() {
    for (value, says) in [
        ("rve_vtk", "no `:`"),
        (":1.1", "no directory"),
        ("out:", "``"),
        ("out:1", "`1`"),
        ("out:1.1,x.2", "`x.2`"),
        ("out:0.0", "`0.0`"),
        ("out:1.-1", "`1.-1`"),
    ] {
        let e = VtkSpec::parse(value).unwrap_err().to_string();
        assert!(
            e.contains(UMAT_VTK_VAR) && e.contains(&format!("`{value}`")),
            "{e}"
        );
        assert!(
            e.contains(says) && e.contains("the analysis goes on"),
            "{e}"
        );
    }
    assert_eq!(
        VtkSpec::parse(" a:b/c : 3.4, 3.4 ,5.6").unwrap(),
        VtkSpec {
            dir: PathBuf::from("a:b/c"),
            points: vec![(3, 4), (5, 6)]
        }
    );
    // A directory that cannot be created: a path under a regular file.
    let file = temp("file");
    std::fs::write(&file, "x").unwrap();
    let e = VtkDump::from_value(&format!("{}/sub:1.1", file.display()))
        .err()
        .unwrap();
    assert!(
        e.starts_with("mesorve: MESORVE_UMAT_VTK") && e.contains("cannot create"),
        "{e}"
    );
    std::fs::remove_file(&file).unwrap();
}

#[test]
fn a_write_failure_does_not_fail_the_call() {
    let dir = temp("gone");
    let table = umat(Some(
        VtkDump::from_value(&format!("{}:1.1", dir.display())).unwrap(),
    ));
    std::fs::remove_dir_all(&dir).unwrap();
    let answers = drive(&table, 1, statev_len() + 5);
    let reference = drive(&umat(None), 1, statev_len() + 5);
    assert_eq!(answers, reference);
    let vtk = table.vtk().unwrap();
    assert_eq!((vtk.written(), vtk.failures()), (0, 3 * INCREMENTS as u64));
    assert!(!dir.exists());
}

/// IMPL-EX past the peak and back: the increments that reuse their step's factorization
/// (unloading) get no file and are counted; every file written holds its answer.
#[test]
fn implex_increments_without_a_fluctuation_get_no_file() {
    let cmname = "paper_rve_host_implex";
    let file = common::repo(&format!("scenes/{cmname}.toml"));
    let nstatv = cache::model_for_file(&file).unwrap().statev_len() + 5;
    let dir = temp("implex");
    let table = umat(Some(
        VtkDump::from_value(&format!("{}:1.1", dir.display())).unwrap(),
    ));
    let mut path: Vec<f64> = (1..=INCREMENTS)
        .map(|k| END * k as f64 / INCREMENTS as f64)
        .collect();
    path.extend((1..=6).map(|k| END * (1.0 - k as f64 / 8.0)));
    let (mut kept, mut start, mut stresses) = (vec![0.0; nstatv], 0.0, Vec::new());
    for (k, &eps) in path.iter().enumerate() {
        let (stress, statev) = call_from(&table, cmname, 1, k + 1, [start, eps], &kept);
        call_from(&table, cmname, 1, k + 1, [start, eps], &kept);
        stresses.push(stress);
        (kept, start) = (statev, eps);
    }
    let vtk = table.vtk().unwrap();
    assert!(vtk.skipped() > 0, "no IMPL-EX increment reused its step");
    assert_eq!(vtk.failures(), 0);
    let pvd = std::fs::read_to_string(dir.join(VtkDump::index_name(1, 1))).unwrap();
    let mut listed = 0;
    for (k, (eps, stress)) in path.iter().zip(&stresses).enumerate() {
        let name = VtkDump::file_name(1, 1, 1, k as i32 + 1);
        let exists = dir.join(&name).exists();
        assert_eq!(exists, pvd.contains(&format!("\"{name}\"")), "{name}");
        if !exists {
            continue;
        }
        listed += 1;
        let (strain, avg, _) = file_measures(&read_vtu(&dir.join(&name)));
        assert!(
            (strain[0] - eps).abs() <= 1e-11 * END,
            "{name}: {strain:?} against {eps}"
        );
        let scale = stress.iter().fold(0.0f64, |m, s| m.max(s.abs()));
        let err = (0..3).fold(0.0f64, |m, i| m.max((avg[i] - stress[i]).abs())) / scale;
        assert!(err <= 1e-9, "{name}: {avg:?} against {stress:?}");
    }
    assert_eq!(listed as u64 + vtk.skipped(), path.len() as u64);
    std::fs::remove_dir_all(&dir).unwrap();
}

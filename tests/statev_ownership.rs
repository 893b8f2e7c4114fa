//! The state a host hands over in `STATEV` must be this point's: the UMAT refuses a
//! valid state of another point, of an older increment, of another scene, of other
//! `PROPS`, of another integration, of an edited scene or mesh file, and an all-zero
//! `STATEV` at a strained point, each with a message, `PNEWDT` < 1, `STRESS` and
//! `STATEV` untouched. The same state at its own strain answers at any point; a
//! comment-only edit of the scene is no change; `*DEPVAR` short of the state is an error
//! that names the count; a `STATEV` of format 1 (no fingerprint) still runs.
//!
//! The path is the paper's §5.2.2 cycle (`scenes/paper_rve_cycle.toml`): increment `k`
//! ends at `path[k]`, tension to 2.3e-4 in 20 increments (peak at 18, snap-back at 19).

mod common;

use std::path::{Path, PathBuf};

use rve::host::{SearchPath, Umat, UmatOutputs};

const UNTOUCHED: f64 = 7.0;

fn path() -> Vec<[f64; 3]> {
    let scene = common::scene("scenes/paper_rve_cycle.toml");
    rve::scene::path_points(&scene.spec.path)
}

/// A host's material: a scene directory, a `CMNAME` and `PROPS`, over one UMAT table.
struct Host {
    umat: Umat,
    cmname: String,
    props: Vec<f64>,
}

/// What one call gave: `STRESS`, `PNEWDT`, the `STATEV` after it, and the outcome.
struct Called {
    stress: Vec<f64>,
    pnewdt: f64,
    statev: Vec<f64>,
    result: Result<(), String>,
}

impl Host {
    fn new(dir: &Path, cmname: &str, props: &[f64]) -> Self {
        Host {
            umat: Umat::new(SearchPath::new([dir.to_path_buf()])),
            cmname: cmname.into(),
            props: props.to_vec(),
        }
    }

    /// One call of point `noel` in increment `k`: from `STRAN` = `path[k-1]` to
    /// `path[k]`, with `statev` as handed over.
    fn call(&self, noel: i32, k: usize, statev: &[f64]) -> Called {
        let path = path();
        let start = if k == 0 { [0.0; 3] } else { path[k - 1] };
        self.call_at(noel, k, start, path[k], statev)
    }

    fn call_at(
        &self,
        noel: i32,
        k: usize,
        start: [f64; 3],
        end: [f64; 3],
        statev: &[f64],
    ) -> Called {
        let dstran: Vec<f64> = (0..3).map(|c| end[c] - start[c]).collect();
        let (mut stress, mut ddsdde, mut pnewdt) = (vec![UNTOUCHED; 3], vec![0.0; 9], 1e36);
        let mut statev = statev.to_vec();
        let c = common::cycle_call(&self.cmname, &self.props, &start, &dstran, noel, k);
        let mut out = UmatOutputs {
            stress: &mut stress,
            ddsdde: &mut ddsdde,
            statev: &mut statev,
            pnewdt: &mut pnewdt,
        };
        let result = self
            .umat
            .call(&c, &mut out)
            .map(|_| ())
            .map_err(|f| f.to_string());
        Called {
            stress,
            pnewdt,
            statev,
            result,
        }
    }

    /// Point `noel` through increments `0..end`, keeping each call's `STATEV`; returns
    /// the `STATEV` at the end and the stress of every increment.
    fn run(
        &self,
        noel: i32,
        range: std::ops::Range<usize>,
        mut statev: Vec<f64>,
    ) -> (Vec<f64>, Vec<Vec<f64>>) {
        let mut stresses = Vec::new();
        for k in range {
            let called = self.call(noel, k, &statev);
            called
                .result
                .unwrap_or_else(|e| panic!("increment {k}: {e}"));
            statev = called.statev;
            stresses.push(called.stress);
        }
        (statev, stresses)
    }
}

/// A scene directory of its own with `PAPER.toml` (the cycle scene, with `edits`).
fn scene_dir(name: &str, edits: &[(&str, &str)]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mesorve-ownership-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    write_scene(&dir, edits);
    dir
}

fn write_scene(dir: &Path, edits: &[(&str, &str)]) {
    let mut text = std::fs::read_to_string(common::repo("scenes/paper_rve_cycle.toml")).unwrap();
    for (from, to) in edits {
        assert!(text.contains(from), "scene text has no `{from}`");
        text = text.replacen(from, to, 1);
    }
    std::fs::write(dir.join("PAPER.toml"), text).unwrap();
}

fn statev_len(dir: &Path) -> usize {
    rve::model::cache::model_for_file(&dir.join("PAPER.toml"))
        .unwrap()
        .statev_len()
}

/// The call was refused as the table asks: a message containing `expect`,
/// `PNEWDT` < 1, `STRESS` and `STATEV` as they came.
fn assert_refused(what: &str, called: &Called, handed: &[f64], expect: &str) {
    let message = called.result.as_ref().expect_err(what);
    println!("{what}: {message}");
    assert!(message.contains(expect), "{what}: {message}");
    assert!(called.pnewdt < 1.0, "{what}: PNEWDT {}", called.pnewdt);
    assert_eq!(called.stress, vec![UNTOUCHED; 3], "{what}: STRESS written");
    assert_eq!(called.statev, handed, "{what}: STATEV changed");
}

#[test]
fn another_points_and_stale_states_are_refused_and_the_own_state_answers() {
    let dir = scene_dir("points", &[]);
    let n = statev_len(&dir);
    let host = Host::new(&dir, "PAPER", &[]);
    let (damaged, _) = host.run(1, 0..20, vec![0.0; n]); // committed at path[19], past the snap
    let (elastic, _) = host.run(2, 0..5, vec![0.0; n]); // committed at path[4]
    let (at_10, _) = host.run(3, 0..11, vec![0.0; n]); // committed at path[10]
    let cases = [
        (
            "another point's, damaged, to a point at a smaller strain",
            4,
            6,
            &damaged,
        ),
        (
            "another point's, elastic, to a damaged point",
            5,
            20,
            &elastic,
        ),
        ("a stale one (two increments old)", 6, 13, &at_10),
    ];
    for (what, noel, k, statev) in cases {
        let called = host.call(noel, k, statev);
        assert_refused(
            what,
            &called,
            statev,
            "not the state of this point at this increment",
        );
    }
    // The same state at its own strain answers at a new point, as at its own.
    let own = host.call(3, 11, &at_10);
    let moved = host.call(7, 11, &at_10);
    own.result.unwrap();
    moved.result.unwrap();
    assert_eq!(moved.stress, own.stress);
    assert_eq!(moved.statev, own.statev);
}

#[test]
fn states_of_other_materials_are_refused_naming_both_fingerprints() {
    let paper = scene_dir("paper", &[]);
    let n = statev_len(&paper);
    let (written, _) = Host::new(&paper, "PAPER", &[]).run(1, 0..10, vec![0.0; n]);
    let shear = scene_dir(
        "shear",
        &[(
            "beta = 0.707,",
            "beta = 0.707, contact_shear = \"cohesive\",",
        )],
    );
    let implex = scene_dir(
        "implex",
        &[("[solver]", "[solver]\nintegration = \"implex\"")],
    );
    assert_eq!(
        statev_len(&shear),
        n,
        "the same size: only the fingerprint tells them apart"
    );
    let n_implex = statev_len(&implex);
    let mut longer = written.clone();
    longer.resize(n_implex, 0.0);
    let cases = [
        (
            "another scene of the same size",
            Host::new(&shear, "PAPER", &[]),
            &written,
        ),
        (
            "an implicit state to IMPL-EX",
            Host::new(&implex, "PAPER", &[]),
            &longer,
        ),
        (
            "other PROPS(1)",
            Host::new(&paper, "PAPER", &[3.6]),
            &written,
        ),
    ];
    for (what, host, statev) in cases {
        let called = host.call(1, 10, statev);
        assert_refused(what, &called, statev, "fingerprint");
    }
    // PROPS(1) = 3.6 written, 4 (the scene's own value) handed: refused; the scene's value
    // through PROPS is the same material as no PROPS.
    let weak = Host::new(&paper, "PAPER", &[3.6]);
    let (weak_state, _) = weak.run(1, 0..10, vec![0.0; n]);
    let called = Host::new(&paper, "PAPER", &[4.0]).call(1, 10, &weak_state);
    assert_refused("PROPS(1) 3.6 then 4", &called, &weak_state, "fingerprint");
    Host::new(&paper, "PAPER", &[4.0])
        .call(1, 10, &written)
        .result
        .unwrap();
}

#[test]
fn props_changed_mid_analysis_are_refused_in_the_same_table() {
    let dir = scene_dir("midway", &[]);
    let n = statev_len(&dir);
    let mut host = Host::new(&dir, "PAPER", &[]);
    let (statev, _) = host.run(1, 0..8, vec![0.0; n]);
    host.props = vec![3.6];
    let called = host.call(1, 8, &statev);
    assert_refused(
        "PROPS changed mid-analysis",
        &called,
        &statev,
        "fingerprint",
    );
}

#[test]
fn an_edited_scene_between_restart_parts_is_refused_unless_only_comments_changed() {
    let dir = scene_dir("restart", &[]);
    let n = statev_len(&dir);
    let whole = Host::new(&dir, "PAPER", &[]).run(1, 0..16, vec![0.0; n]).1;
    let (middle, _) = Host::new(&dir, "PAPER", &[]).run(1, 0..8, vec![0.0; n]);
    write_scene(
        &dir,
        &[(
            "[cell]",
            "# edited between the two parts\n[cell]  # a comment",
        )],
    );
    let (_, second) = Host::new(&dir, "PAPER", &[]).run(1, 8..16, middle.clone());
    assert_eq!(second, whole[8..], "a comment-only edit is no change");
    write_scene(&dir, &[("sigma_c = 4.0", "sigma_c = 3.8")]);
    let called = Host::new(&dir, "PAPER", &[]).call(1, 8, &middle);
    assert_refused(
        "sigma_c edited between the parts",
        &called,
        &middle,
        "fingerprint",
    );
}

#[test]
fn a_changed_mesh_file_is_refused() {
    let dir = std::env::temp_dir().join(format!("mesorve-ownership-{}-gmsh", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let msh = std::fs::read_to_string(common::repo("tests/data/gmsh/two_circles_v41.msh")).unwrap();
    std::fs::write(dir.join("mesh.msh"), &msh).unwrap();
    let scene = std::fs::read_to_string(common::repo("scenes/gmsh_two_circles.toml"))
        .unwrap()
        .replace("../tests/data/gmsh/two_circles_v41.msh", "mesh.msh");
    std::fs::write(dir.join("PAPER.toml"), scene).unwrap();
    let n = statev_len(&dir);
    let (statev, _) = Host::new(&dir, "PAPER", &[]).run(1, 0..6, vec![0.0; n]);
    // The same mesh file again: a restart in a new process answers.
    Host::new(&dir, "PAPER", &[])
        .call(1, 6, &statev)
        .result
        .unwrap();
    // One node moved by 1e-3 mm: the same sizes, another mesh. The scene text is the same,
    // so drop the process's cached model first (a new process).
    let moved = move_first_interior_node(&msh);
    std::fs::write(dir.join("mesh.msh"), moved).unwrap();
    std::fs::write(
        dir.join("PAPER.toml"),
        std::fs::read_to_string(dir.join("PAPER.toml")).unwrap() + "\n",
    )
    .unwrap();
    assert_eq!(statev_len(&dir), n);
    let called = Host::new(&dir, "PAPER", &[]).call(1, 6, &statev);
    assert_refused("a changed mesh file", &called, &statev, "fingerprint");
}

/// The MSH 4.1 text with the x coordinate of a node strictly inside the cell moved.
fn move_first_interior_node(msh: &str) -> String {
    let mut lines: Vec<String> = msh.lines().map(String::from).collect();
    let nodes = lines.iter().position(|l| l == "$Nodes").unwrap();
    for line in lines.iter_mut().skip(nodes + 2) {
        let xyz: Vec<f64> = line
            .split_whitespace()
            .filter_map(|t| t.parse().ok())
            .collect();
        if xyz.len() == 3 && xyz[0] > 1.0 && xyz[0] < 9.0 && xyz[1] > 1.0 && xyz[1] < 9.0 {
            *line = format!("{} {} {}", xyz[0] + 1e-3, xyz[1], xyz[2]);
            return lines.join("\n") + "\n";
        }
    }
    panic!("no interior node found");
}

#[test]
fn an_all_zero_statev_at_a_strained_point_is_a_lost_state_unless_the_scene_says_virgin() {
    let dir = scene_dir("zero", &[]);
    let n = statev_len(&dir);
    let zeros = vec![0.0; n];
    let called = Host::new(&dir, "PAPER", &[]).call(1, 10, &zeros);
    assert_refused(
        "all zeros at a strained point",
        &called,
        &zeros,
        "did not carry this point's state",
    );
    let message = called.result.unwrap_err();
    assert!(
        message.contains("contact pair") && message.contains("zero_at_strain"),
        "{message}"
    );
    // Under the switch: the virgin RVE at the host's strain, as a point that starts there.
    let virgin = scene_dir(
        "virgin",
        &[(
            "[solver]",
            "[statev]\nzero_at_strain = \"virgin\"\n\n[solver]",
        )],
    );
    let host = Host::new(&virgin, "PAPER", &[]);
    let readded = host.call(1, 10, &zeros);
    readded.result.unwrap();
    let path = path();
    let fresh = host.call_at(2, 0, [0.0; 3], path[10], &zeros);
    assert_eq!(readded.stress, fresh.stress);
}

#[test]
fn the_strain_check_has_a_documented_way_out() {
    let dir = scene_dir(
        "unchecked",
        &[("[solver]", "[statev]\ncheck_strain = false\n\n[solver]")],
    );
    let n = statev_len(&dir);
    let host = Host::new(&dir, "PAPER", &[]);
    let (at_10, _) = host.run(3, 0..11, vec![0.0; n]);
    // A host whose STRAN means something else: the state's own strain is used.
    host.call_at(1, 11, [0.0; 3], path()[11], &at_10)
        .result
        .unwrap();
}

#[test]
fn a_depvar_short_of_the_state_is_an_error_naming_the_count() {
    let dir = scene_dir("short", &[]);
    let n = statev_len(&dir);
    let host = Host::new(&dir, "PAPER", &[]);
    for nstatv in [rve::host::TABLE_MODE_MAX_NSTATV + 1, n / 2, n - 1] {
        let zeros = vec![0.0; nstatv];
        let called = host.call(1, 0, &zeros);
        assert_refused(
            "NSTATV short",
            &called,
            &zeros,
            &format!("set *DEPVAR to at least {n}"),
        );
    }
    // Up to the mirrors' count: the library's table, as documented.
    for nstatv in 0..=rve::host::TABLE_MODE_MAX_NSTATV {
        host.call(10 + nstatv as i32, 0, &vec![0.0; nstatv])
            .result
            .unwrap();
    }
}

/// The `STATEV` of format 1 (the first format, without the fingerprint and the time) that
/// `values` (format 2) stand for: the payload less its last 9 bytes (the time, bincode's
/// `Some` tag and the f64), entry 1 = the payload length, entry 3 = the CRC-32C of entries
/// 0-2 and the payload (docs/statev.md).
fn as_format_1(values: &[f64]) -> Vec<f64> {
    let mut e: Vec<u64> = values.iter().map(|&v| v as u64).collect();
    let len = (e[1] % (1 << 24)) as usize;
    let mut payload: Vec<u8> = e[4..4 + len.div_ceil(6)]
        .iter()
        .flat_map(|v| v.to_le_bytes().into_iter().take(6))
        .take(len)
        .collect();
    assert_eq!(payload[len - 9], 1, "the time is there");
    payload.truncate(len - 9);
    let len = payload.len();
    e[0] = (e[0] >> 16 << 16) | 1;
    e[1] = len as u64;
    let packed: Vec<u64> = payload
        .chunks(6)
        .map(|c| {
            let mut bytes = [0u8; 8];
            bytes[..c.len()].copy_from_slice(c);
            u64::from_le_bytes(bytes)
        })
        .collect();
    e[4..].fill(0);
    e[4..4 + packed.len()].copy_from_slice(&packed);
    let mut bytes: Vec<u8> = e[..3].iter().flat_map(|v| v.to_le_bytes()).collect();
    bytes.extend_from_slice(&payload);
    e[3] = u64::from(crc32c::crc32c(&bytes));
    e.into_iter().map(|v| v as f64).collect()
}

#[test]
fn a_format_1_statev_runs_on_unverified_and_is_written_back_in_format_2() {
    let dir = scene_dir("format1", &[]);
    let n = statev_len(&dir);
    let host = Host::new(&dir, "PAPER", &[]);
    let (current, _) = host.run(1, 0..10, vec![0.0; n + 3]);
    let old = as_format_1(&current);
    assert_ne!(old[..n], current[..n]);
    let from_old = host.call(2, 10, &old);
    let from_current = host.call(3, 10, &current);
    from_old.result.unwrap();
    from_current.result.unwrap();
    assert_eq!(from_old.stress, from_current.stress);
    assert_eq!(
        from_old.statev[..n],
        from_current.statev[..n],
        "written back as format 2"
    );
    // Still checked for corruption and for its strain.
    let mut changed = old.clone();
    changed[20] += 1.0;
    assert_refused(
        "a changed format 1 value",
        &host.call(4, 10, &changed),
        &changed,
        "checksum",
    );
    assert_refused(
        "a format 1 state of another increment",
        &host.call(5, 12, &old),
        &old,
        "not the state of this point",
    );
}

/// An element re-added by CalculiX 2.20's `*MODEL CHANGE, ADD`: ccx hands it the
/// `STATEV` of its last call before the removal, with that state's own strain as `STRAN`
/// (docs/calculix.md measures it) but at a later time. Refused unless the scene says the
/// host's time means something else.
#[test]
fn a_state_of_an_earlier_time_is_refused_as_a_readded_element() {
    let dir = scene_dir("readded", &[]);
    let n = statev_len(&dir);
    let host = Host::new(&dir, "PAPER", &[]);
    let (at_10, _) = host.run(1, 0..11, vec![0.0; n]); // committed at path[10], time 1.1
    let path = path();
    // Step 3 of the check's deck: the old strain as STRAN, time 2.0, a new strain.
    let readded = |host: &Host| {
        let (k, end) = (20, [path[10][0] * 0.5, 0.0, 0.0]);
        host.call_at(1, k, path[10], end, &at_10)
    };
    let called = readded(&host);
    assert_refused(
        "a re-added element's old state",
        &called,
        &at_10,
        "the state of another increment",
    );
    let message = called.result.unwrap_err();
    assert!(
        message.contains("*MODEL CHANGE") && message.contains("check_time"),
        "{message}"
    );
    let lax = scene_dir(
        "readded-lax",
        &[("[solver]", "[statev]\ncheck_time = false\n\n[solver]")],
    );
    readded(&Host::new(&lax, "PAPER", &[])).result.unwrap();
}

//! Instances of one scene share one model: 10^4 inits mesh the scene once. (Alone in its
//! test binary, so the process-wide build counter is exact.)

mod common;

use std::ffi::CString;

use rve::ffi::*;

#[test]
fn ten_thousand_instances_build_one_model() {
    let path = CString::new(common::repo("scenes/paper_rve.toml").to_str().unwrap()).unwrap();
    let text =
        CString::new(std::fs::read_to_string(common::repo("scenes/paper_rve.toml")).unwrap())
            .unwrap();
    let before = rve_model_builds();
    let mut handles = Vec::new();
    for _ in 0..10_000 {
        let mut h = 0;
        assert_eq!(unsafe { rve_init_file(path.as_ptr(), &mut h) }, 0);
        handles.push(h);
    }
    assert_eq!(rve_model_builds() - before, 1);
    // The same scene as text is another key (base directory), built once more.
    for _ in 0..100 {
        let mut h = 0;
        assert_eq!(
            unsafe { rve_init_text(text.as_ptr(), std::ptr::null(), &mut h) },
            0
        );
        handles.push(h);
    }
    assert_eq!(rve_model_builds() - before, 2);
    let mut h = 0;
    assert_eq!(unsafe { rve_clone_model(handles[0], &mut h) }, 0);
    handles.push(h);
    assert_eq!(rve_model_builds() - before, 2);
    let unique: std::collections::HashSet<_> = handles.iter().collect();
    assert_eq!(unique.len(), handles.len());
    for h in &handles {
        assert_eq!(rve_free(*h), 0);
    }
    assert_eq!(live_instances(), 0);
    // Freed ids stay invalid even after their slots are reused.
    let mut fresh = 0;
    assert_eq!(unsafe { rve_init_file(path.as_ptr(), &mut fresh) }, 0);
    assert!(!handles.contains(&fresh));
    for h in &handles[..10] {
        assert_eq!(rve_commit(*h), RveStatus::BadHandle as u32);
    }
    assert_eq!(rve_free(fresh), 0);
}

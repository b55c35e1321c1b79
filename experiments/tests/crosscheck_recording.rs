//! The cross-check without ngspice: every netlist it writes has its recorded ngspice run
//! (`data/recorded/ngspice/crosscheck.json`), so `crosscheck` succeeds on a machine without
//! ngspice and says where ngspice's numbers came from. A netlist that changes without the
//! recording being rewritten (`crosscheck --record-ngspice`) fails this test.

use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_crosscheck");

#[test]
fn every_netlist_of_the_cross_check_has_its_recorded_run() {
    let out = std::env::temp_dir().join(format!("endstop-crosscheck-rec-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    // A PATH holding only git (for the provenance): no ngspice to fall back on.
    let path = out.join("path");
    std::fs::create_dir_all(&path).unwrap();
    let git = Command::new("sh")
        .args(["-c", "command -v git"])
        .output()
        .unwrap();
    let git = String::from_utf8(git.stdout).unwrap();
    std::os::unix::fs::symlink(git.trim(), path.join("git")).unwrap();
    let o = Command::new(BIN)
        .env("PATH", &path)
        .env("ENDSTOP_OUTPUT_DIR", &out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let md = std::fs::read_to_string(out.join("book-generated/crosscheck/numbers.md")).unwrap();
    assert!(
        md.contains("its runs recorded in `data/recorded/ngspice/crosscheck.json`"),
        "{}",
        &md[..md.len().min(400)]
    );
    assert!(
        !md.contains("ngspice failed"),
        "a row has no ngspice numbers"
    );
    std::fs::remove_dir_all(&out).ok();
}

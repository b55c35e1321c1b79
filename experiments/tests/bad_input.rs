//! An experiment given a bad parameter file stops with a message naming the field, exit code 1,
//! no panic and no output written.

fn text(name: &str) -> String {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    std::fs::read_to_string(root.join(format!("data/{name}.toml"))).unwrap()
}

fn replace(text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "{from} not found");
    text.replacen(from, to, 1)
}

#[test]
fn an_experiment_with_a_bad_parameter_file_exits_nonzero_naming_the_field() {
    let dir = std::env::temp_dir().join(format!("endstop-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("prototype1.toml"),
        replace(&text("prototype1"), "mass_kg = 2.8e-6", "mass_kg = -2.8e-6"),
    )
    .unwrap();
    std::fs::write(dir.join("prototype2.toml"), text("prototype2")).unwrap();
    for bin in [env!("CARGO_BIN_EXE_table3"), env!("CARGO_BIN_EXE_fig05")] {
        let out = std::process::Command::new(bin)
            .env("ENDSTOP_DATA_DIR", &dir)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{bin} accepted a negative mass");
        assert_eq!(out.status.code(), Some(1), "{bin}: {stderr}");
        assert!(stderr.contains("mechanics.mass_kg"), "{bin}: {stderr}");
        assert!(!stderr.contains("panicked"), "{bin} panicked: {stderr}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

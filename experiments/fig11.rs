//! fig11: not implemented yet (placeholder so the package layout is complete).
fn main() {
    eprintln!("[fig11] not implemented yet");
    std::process::exit(2);
}

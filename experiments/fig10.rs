//! fig10: not implemented yet (placeholder so the package layout is complete).
fn main() {
    eprintln!("[fig10] not implemented yet");
    std::process::exit(2);
}

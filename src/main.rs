//! The `poser` command-line entry point; everything lives in [`poser::cli`].
fn main() -> std::process::ExitCode {
    // Like every Unix tool, end quietly when the reader of stdout goes away
    // (`poser dive … --json | head`): Rust ignores SIGPIPE by default, which turns a closed
    // pipe into a "Broken pipe" panic in `println!`; restore the default action.
    #[cfg(unix)]
    // SAFETY: called first thing, before any thread exists; only resets a signal disposition.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    poser::cli::main()
}

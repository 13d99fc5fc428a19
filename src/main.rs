//! The `poser` command-line entry point; everything lives in [`poser::cli`].
fn main() -> std::process::ExitCode {
    poser::cli::main()
}

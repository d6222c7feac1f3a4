use std::process::ExitCode;

fn main() -> ExitCode {
    // An interrupted run leaves no staging folder behind.
    contactlab::io::run_folder::remove_on_interrupt();
    contactlab::cli::main()
}

use std::process::ExitCode;

fn main() -> ExitCode {
    contactlab::cli::main()
}

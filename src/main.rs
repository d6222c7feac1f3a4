use std::process::ExitCode;

/// The system allocator, noting an allocation it refuses (see
/// [`contactlab::allocator::report_out_of_memory_on_abort`]).
#[global_allocator]
static ALLOCATOR: contactlab::allocator::Recording = contactlab::allocator::Recording;

fn main() -> ExitCode {
    // An allocation that fails beyond every estimate is one line and exit
    // code 3, not an abort.
    contactlab::allocator::report_out_of_memory_on_abort();
    // An interrupted run leaves no staging folder behind.
    contactlab::io::run_folder::remove_on_interrupt();
    contactlab::cli::main()
}

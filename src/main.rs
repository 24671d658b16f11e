fn main() -> std::process::ExitCode {
    dibench::cli::main_with(Vec::new())
}

fn main() {
    std::process::exit(vesselmsr::cli::run());
}

//! `cargo run --release -p polyphase-solver --example bench [pressure|viscosity]
//! [mic0|multigrid] [RES...]`: prints the solver benchmark table (default: both solves with
//! both preconditioners at resolutions 64 and 128).

use polyphase_solver::PreconditionerKind;

fn main() -> Result<(), polyphase_solver::SolverError> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let res: Vec<usize> = args.iter().filter_map(|a| a.parse().ok()).collect();
    let res = if res.is_empty() { vec![64, 128] } else { res };
    let only = |name: &str| args.iter().any(|a| a == name);
    let (p, v) = match (only("pressure"), only("viscosity")) {
        (false, false) => (true, true),
        sel => sel,
    };
    let pre = if only("mic0") {
        Some(PreconditionerKind::Mic0)
    } else if only("multigrid") {
        Some(PreconditionerKind::Multigrid)
    } else {
        None
    };
    let rows = polyphase_solver::bench::run_selected(&res, p, v, pre)?;
    print!("{}", polyphase_solver::bench::format_table(&rows));
    Ok(())
}

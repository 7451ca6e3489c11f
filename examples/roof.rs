//! Scordelis–Lo roof under refinement. Reference (Kirchhoff–Love): 0.3006 (Kiendl 2011),
//! 0.3005925 (GeoPDEs), the error column against the former.
//! Run: `cargo run --release --example roof`
use kshell::scene::roof::ScordelisLo;
fn main() {
    println!(
        "{:>8} {:>8} {:>12} {:>12}",
        "mesh", "dofs", "w_mid", "rel. error"
    );
    for n in [4, 8, 16, 32, 64] {
        let (w, dofs) = ScordelisLo {
            n_length: n,
            n_arc: n,
        }
        .run()
        .unwrap();
        println!(
            "{:>8} {:>8} {:>12.6} {:>12.3e}",
            format!("{n}x{n}"),
            dofs,
            w,
            w / 0.3006 - 1.0
        );
    }
}

//! Writes the stability atlas to paper_repro/stability/atlas.csv and atlas.md.
//! Run: `cargo run --release --example stability_atlas` (add `--reduced` for the CI size).

fn main() -> std::io::Result<()> {
    let reduced = std::env::args().any(|a| a == "--reduced");
    let rows = kshell::atlas::atlas(reduced);
    std::fs::create_dir_all("paper_repro/stability")?;
    std::fs::write(
        "paper_repro/stability/atlas.csv",
        kshell::atlas::to_csv(&rows),
    )?;
    let md = kshell::atlas::to_markdown(&rows);
    std::fs::write("paper_repro/stability/atlas.md", &md)?;
    print!("{md}");
    Ok(())
}

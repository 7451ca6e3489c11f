//! Writes the stability atlas to paper_repro/stability/: atlas.csv, atlas.md (the per-case
//! summary, then every row) and atlas.svg (time against case for every method).
//! Run: `cargo run --release --example stability_atlas` (add `--reduced` for the CI size).

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let reduced = std::env::args().any(|a| a == "--reduced");
    let rows = kshell::atlas::atlas(reduced);
    let dir = std::path::Path::new("paper_repro/stability");
    std::fs::create_dir_all(dir)?;
    std::fs::write(dir.join("atlas.csv"), kshell::atlas::to_csv(&rows))?;
    std::fs::write(dir.join("atlas.svg"), kshell::atlas::to_svg(&rows)?)?;
    let md = format!(
        "# Stability atlas\n\nWritten by `cargo run --release --example stability_atlas`{}.\n\n\
         ## Iterations of each strategy against the fewest any strategy took\n\n{}\n\
         ## Every row\n\nIterations and factorisations count every solve, failed attempts \
         included; for the cantilevers the backward-Euler, refinement and saddle counts are the \
         last load step's.\n\n{}",
        if reduced { " --reduced" } else { "" },
        kshell::atlas::summary(&rows),
        kshell::atlas::to_markdown(&rows)
    );
    std::fs::write(dir.join("atlas.md"), &md)?;
    print!("{md}");
    Ok(())
}

//! The batch manifest: one fabric per row, `fabric` (its folder name under `--out`) and
//! `dataset` (its fabric.toml, relative to the manifest's folder), then optional columns that
//! are `ks-fit fit` options (`model`, `max_degree`, …; an empty cell keeps the default). And
//! the fingerprint of a row's inputs, by which a finished fabric is recognised on a rerun.

use kshell::limits::MAX_BATCH_ROWS;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Manifest columns passed to `ks-fit fit` as `--name value` (underscores become hyphens).
pub const FIT_COLUMNS: [&str; 20] = [
    "model",
    "max_degree",
    "degree",
    "mesh_ladder",
    "method",
    "protocol",
    "toe",
    "repeat",
    "max_misalign",
    "nodes",
    "max_error",
    "strategy",
    "bending",
    "mesh_check",
    "grading",
    "test_meshes",
    "yarn_rule",
    "shear_coupling",
    "objective",
    "joint",
];

/// Largest manifest read, bytes (a library of a million fabrics is well under it).
const MANIFEST_BYTES: u64 = 64 << 20;

/// One fabric of the manifest.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// 1-based line of the manifest
    pub line: usize,
    pub fabric: String,
    /// the dataset's fabric.toml, resolved against the manifest's folder
    pub dataset: PathBuf,
    /// the dataset as the manifest gives it, and the manifest's folder: the fit runs there on
    /// that path, so that the material records the same dataset however the batch was started
    pub given: String,
    pub folder: PathBuf,
    /// (column, value) of the non-empty option cells, in manifest column order
    pub options: Vec<(String, String)>,
}

impl Row {
    /// The `ks-fit fit` arguments of the row's options.
    pub fn fit_args(&self) -> Vec<String> {
        self.options
            .iter()
            .flat_map(|(k, v)| [format!("--{}", k.replace('_', "-")), v.clone()])
            .collect()
    }

    /// The cloth model the row fits (`fit --model`'s default unless its `model` cell says
    /// otherwise).
    pub fn model(&self) -> &str {
        self.options
            .iter()
            .find(|(k, _)| k == "model")
            .map_or(crate::flags::DEFAULT_MODEL, |(_, v)| v.as_str())
    }
}

/// A folder name a fabric may have: letters, digits, `.`, `_`, `-`, not starting with `.`.
fn valid_name(s: &str) -> bool {
    !s.is_empty()
        && s.len() <= 100
        && !s.starts_with('.')
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-'))
}

/// Reads a manifest; every error names the file and line.
pub fn read_manifest(path: &Path) -> Result<Vec<Row>, String> {
    let name = path.display();
    let text = kshell::io::read_text(path, MANIFEST_BYTES).map_err(|e| format!("{name}: {e}"))?;
    parse_manifest(&text, path)
}

/// [`read_manifest`] on text already read (`path` names it and anchors relative datasets).
pub fn parse_manifest(text: &str, path: &Path) -> Result<Vec<Row>, String> {
    let name = path.display();
    let base = path.parent().unwrap_or(Path::new(""));
    let mut reader = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .flexible(false)
        .from_reader(text.as_bytes());
    let header: Vec<String> = reader
        .headers()
        .map_err(|e| format!("{name}: {e}"))?
        .iter()
        .map(|h| h.to_ascii_lowercase())
        .collect();
    let column = |c: &str| header.iter().position(|h| h == c);
    let (Some(fabric), Some(dataset)) = (column("fabric"), column("dataset")) else {
        return Err(format!(
            "{name}:1: the header must name the columns `fabric` and `dataset` (then any of {}), got `{}`",
            FIT_COLUMNS.join(", "),
            header.join(",")
        ));
    };
    for (i, h) in header.iter().enumerate() {
        if i != fabric && i != dataset && !FIT_COLUMNS.contains(&h.as_str()) {
            return Err(format!(
                "{name}:1: unknown column `{h}`; the columns are fabric, dataset and the fit options {}",
                FIT_COLUMNS.join(", ")
            ));
        }
        if header[..i].contains(h) {
            return Err(format!("{name}:1: the column `{h}` appears twice"));
        }
    }
    let mut rows: Vec<Row> = Vec::new();
    // each fabric's line, to find a repeated name in one pass
    let mut lines: HashMap<String, usize> = HashMap::new();
    for record in reader.records() {
        let record = record.map_err(|e| {
            let line = e.position().map_or(0, |p| p.line());
            format!("{name}:{line}: {e}")
        })?;
        let line = record.position().map_or(0, |p| p.line()) as usize;
        if rows.len() == MAX_BATCH_ROWS {
            return Err(format!(
                "{name}:{line}: more than {MAX_BATCH_ROWS} fabrics in one manifest; split it into several batches"
            ));
        }
        let fab = record[fabric].to_string();
        if !valid_name(&fab) {
            return Err(format!(
                "{name}:{line}: fabric `{fab}` is not a folder name (letters, digits, '.', '_' and '-', not starting with '.')"
            ));
        }
        if let Some(first) = lines.get(&fab) {
            return Err(format!(
                "{name}:{line}: fabric `{fab}` is already on line {first}"
            ));
        }
        lines.insert(fab.clone(), line);
        if record[dataset].is_empty() {
            return Err(format!("{name}:{line}: fabric `{fab}` has no dataset"));
        }
        let options = header
            .iter()
            .enumerate()
            .filter(|&(i, _)| i != fabric && i != dataset && !record[i].is_empty())
            .map(|(i, h)| (h.clone(), record[i].to_string()))
            .collect();
        rows.push(Row {
            line,
            fabric: fab,
            dataset: base.join(&record[dataset]),
            given: record[dataset].to_string(),
            folder: base.to_path_buf(),
            options,
        });
    }
    if rows.is_empty() {
        return Err(format!("{name}: the manifest lists no fabric"));
    }
    Ok(rows)
}

/// 64-bit FNV-1a: a stable fingerprint (the same on every machine and Rust version), enough
/// to notice that an input changed; not a defence against deliberate collisions.
#[derive(Clone, Copy)]
pub struct Fnv(u64);

impl Fnv {
    pub fn new() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }

    pub fn add(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
        // a separator, so that ("ab", "c") and ("a", "bc") differ
        self.0 ^= 0xff;
        self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
    }

    pub fn hex(self) -> String {
        format!("{:016x}", self.0)
    }
}

/// The fingerprint of a row's inputs: ks-fit's version, the row's options, the dataset file
/// and every curve and shape file it names (as far as the dataset can be read: a broken one is
/// fingerprinted by its own bytes, and its fit fails and is retried on every rerun anyway).
pub fn inputs_hash(row: &Row) -> Result<String, String> {
    let mut h = Fnv::new();
    h.add(concat!("ks-fit ", env!("CARGO_PKG_VERSION")).as_bytes());
    for (k, v) in &row.options {
        h.add(k.as_bytes());
        h.add(v.as_bytes());
    }
    let shown = row.dataset.display();
    // bounded and regular, as the fit reads it (a FIFO would block the hash forever)
    let text = kshell::io::read_text(&row.dataset, 16 << 20)
        .map_err(|e| format!("{shown}: cannot read: {e}"))?;
    h.add(text.as_bytes());
    if let Ok((data, _)) = kshell::dataset::load_dataset(&row.dataset) {
        let dir = row.dataset.parent().unwrap_or(Path::new(""));
        let files = data.tensile.iter().map(|t| &t.curve);
        for f in files.chain(data.shapes.iter().map(|s| &s.obj)) {
            h.add(f.to_string_lossy().as_bytes());
            if let Ok(b) = std::fs::read(dir.join(f)) {
                h.add(&b);
            }
        }
    }
    Ok(h.hex())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Vec<Row>, String> {
        parse_manifest(text, Path::new("lib/manifest.csv"))
    }

    /// Every option column is a `ks-fit fit` flag that takes a value.
    #[test]
    fn fit_columns_are_fit_flags() {
        use clap::Args;
        let fit = crate::fit::FitArgs::augment_args(clap::Command::new("fit"));
        for c in FIT_COLUMNS {
            let long = c.replace('_', "-");
            let flag = fit.get_arguments().find(|a| a.get_long() == Some(&long));
            assert!(flag.is_some_and(|a| a.get_action().takes_values()), "{c}");
        }
    }

    #[test]
    fn rows_resolve_datasets_and_pass_options() {
        let rows = parse(
            "# a library\nfabric,dataset,model,max_degree\ncotton,cotton/fabric.toml,,2\n\nsilk , /data/silk.toml,stvk-ds,\n",
        )
        .unwrap();
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[0].line, 3);
        assert_eq!(rows[0].dataset, PathBuf::from("lib/cotton/fabric.toml"));
        assert_eq!(rows[0].fit_args(), ["--max-degree", "2"]);
        assert_eq!(rows[0].model(), "kl");
        assert_eq!(rows[1].fabric, "silk");
        assert_eq!(rows[1].dataset, PathBuf::from("/data/silk.toml"));
        assert_eq!(rows[1].fit_args(), ["--model", "stvk-ds"]);
        assert_eq!(rows[1].model(), "stvk-ds");
    }

    #[test]
    fn bad_manifests_name_the_line() {
        for (text, want) in [
            (
                "name,dataset\na,b\n",
                "lib/manifest.csv:1: the header must name",
            ),
            (
                "fabric,dataset,colour\na,b,red\n",
                "lib/manifest.csv:1: unknown column `colour`",
            ),
            (
                "fabric,dataset\na,x.toml\na,y.toml\n",
                "lib/manifest.csv:3: fabric `a` is already on line 2",
            ),
            (
                "fabric,dataset\n../up,x.toml\n",
                "lib/manifest.csv:2: fabric `../up` is not a folder name",
            ),
            ("fabric,dataset\n.hidden,x.toml\n", "is not a folder name"),
            (
                "fabric,dataset\na,\n",
                "lib/manifest.csv:2: fabric `a` has no dataset",
            ),
            ("fabric,dataset\na,b,c\n", "lib/manifest.csv:2:"),
            ("fabric,dataset\n", "lists no fabric"),
            ("fabric,dataset,model,model\na,b,kl,kl\n", "appears twice"),
        ] {
            let err = parse(text).unwrap_err();
            assert!(err.contains(want), "{text:?}: {err}");
        }
    }

    #[test]
    fn the_fingerprint_is_fixed_and_sees_every_byte() {
        let mut a = Fnv::new();
        a.add(b"ab");
        a.add(b"c");
        let mut b = Fnv::new();
        b.add(b"a");
        b.add(b"bc");
        assert_ne!(a.hex(), b.hex());
        // a fixed value: the fingerprint must not change between builds or machines
        let mut c = Fnv::new();
        c.add(b"");
        assert_eq!(
            c.hex(),
            format!(
                "{:016x}",
                (0xcbf2_9ce4_8422_2325u64 ^ 0xff).wrapping_mul(0x0100_0000_01b3)
            )
        );
    }
}

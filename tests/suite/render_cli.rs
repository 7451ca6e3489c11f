//! `ks-fit render` and the `scene.png` of `ks-fit scene`, driven through the binary: the PNG is
//! written at the size asked for; without any GPU driver the scene still writes its shapes and
//! says why there is no picture; bad input is a one-line error.
//!
//! Where no adapter exists the picture checks are skipped with a note, unless
//! KSHELL_REQUIRE_GPU is set (as CI does after installing Mesa's software driver).

use crate::common::{folder, ks_fit, ks_fit_env, s};

const COTTON: &str = "examples/materials/cotton.toml";

/// Width and height from a PNG's IHDR chunk.
fn png_size(bytes: &[u8]) -> (u32, u32) {
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "not a PNG");
    let be = |i: usize| u32::from_be_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
    (be(16), be(20))
}

fn gpu_required() -> bool {
    std::env::var_os("KSHELL_REQUIRE_GPU").is_some()
}

/// Hides every Vulkan and EGL driver from the loader (render-notes: GL may otherwise be found).
const NO_DRIVERS: [(&str, &str); 3] = [
    ("VK_DRIVER_FILES", "/nonexistent/icd.json"),
    ("VK_ICD_FILENAMES", "/nonexistent/icd.json"),
    ("__EGL_VENDOR_LIBRARY_FILENAMES", "/nonexistent/egl.json"),
];

fn frame_args<'a>(out: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut a = vec![
        "scene",
        "picture-frame",
        "--material",
        COTTON,
        "--mesh",
        "4",
        "--steps",
        "2",
        "--shear-deg",
        "20",
        "--out",
        out,
    ];
    a.extend_from_slice(extra);
    a
}

#[test]
fn a_scene_writes_its_picture_at_the_size_asked_for() {
    let dir = folder("render-scene");
    let out = dir.join("frame");
    let (rc, _, err) = ks_fit(&frame_args(s(&out), &["--image", "96x64"]));
    assert_eq!(rc, 0, "{err}");
    assert!(out.join("shape.obj").exists());
    if err.contains("no scene.png") && !gpu_required() {
        eprintln!("skipped (no GPU adapter): {err}");
        return;
    }
    assert!(err.contains("scene.png 96x64"), "{err}");
    let png = std::fs::read(out.join("scene.png")).unwrap();
    assert_eq!(png_size(&png), (96, 64));

    // the written shape renders too, and --no-image writes none
    let shape = out.join("shape.obj");
    let pic = dir.join("shape.png");
    let (rc, _, err) = ks_fit(&["render", s(&shape), "--out", s(&pic), "--image", "50x40"]);
    assert_eq!(rc, 0, "{err}");
    assert_eq!(png_size(&std::fs::read(&pic).unwrap()), (50, 40));
    let out2 = dir.join("frame2");
    let (rc, _, err) = ks_fit(&frame_args(s(&out2), &["--no-image"]));
    assert_eq!(rc, 0, "{err}");
    assert!(out2.join("shape.obj").exists() && !out2.join("scene.png").exists());
}

#[test]
fn without_a_driver_the_scene_says_so_and_still_writes_the_shapes() {
    let dir = folder("render-nodriver");
    let out = dir.join("frame");
    let (rc, _, err) = ks_fit_env(&frame_args(s(&out), &["--image", "32x32"]), &NO_DRIVERS);
    assert_eq!(rc, 0, "{err}");
    for f in ["shape.obj", "shape.ply", "picture-frame.csv", "scene.toml"] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    assert!(!out.join("scene.png").exists());
    assert!(
        err.contains("no scene.png (no GPU adapter found") && err.contains("mesa-vulkan-drivers"),
        "{err}"
    );
    // `render` has nothing else to do: an error, exit code 2
    let shape = out.join("shape.obj");
    let (rc, _, err) = ks_fit_env(
        &["render", s(&shape), "--out", s(&dir.join("x.png"))],
        &NO_DRIVERS,
    );
    assert_eq!(rc, 2);
    assert!(
        err.starts_with("ks-fit: error: no GPU adapter found"),
        "{err}"
    );
}

#[test]
fn bad_render_input_is_a_one_line_error() {
    let dir = folder("render-bad");
    let obj = dir.join("bad.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nf 1 2 3\n").unwrap();
    let png = dir.join("x.png");
    let (rc, _, err) = ks_fit(&["render", s(&obj), "--out", s(&png)]);
    assert_eq!(rc, 2);
    assert_eq!(
        err.trim(),
        format!(
            "ks-fit: error: {}:3: vertex index 3 is out of range (2 read so far)",
            obj.display()
        )
    );
    let (rc, _, err) = ks_fit(&["render", s(&obj), "--out", s(&png), "--image", "0x10"]);
    assert_eq!(rc, 2);
    assert!(
        err.contains("each side must be a whole number from 1 to 8192"),
        "{err}"
    );
    assert!(!png.exists());
}

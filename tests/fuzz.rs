//! Generator-based fuzzing of the experiment (RON) and glTF loaders: seeded random mutations of
//! real files (byte flips, deletions, duplications, and insertions of syntax tokens), each
//! loaded and required to return Ok or an error, never to panic. Bounded: a fixed number of
//! cases (a few seconds for both loaders) so that CI runs it every time; longer runs set
//! `MANYLIGHTS_FUZZ_CASES` (RON cases; glTF gets half) and `MANYLIGHTS_FUZZ_SEED`.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use manylights_lab::Experiment;
use manylights_scene::gltf_import::{GltfOptions, load};
use rand::{RngExt, SeedableRng};

fn cases() -> usize {
    std::env::var("MANYLIGHTS_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20_000)
}

fn seed(base: u64) -> u64 {
    base + std::env::var("MANYLIGHTS_FUZZ_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0)
}

const TOKENS: [&[u8]; 16] = [
    b"(",
    b")",
    b"[",
    b"]",
    b"{",
    b"}",
    b",",
    b":",
    b"\"",
    b"-1",
    b"1e999",
    b"NaN",
    b"null",
    b"Some(",
    b"999999999999",
    b"\\u0000",
];

fn mutate(rng: &mut rand_pcg::Pcg64, src: &[u8]) -> Vec<u8> {
    let mut v = src.to_vec();
    for _ in 0..rng.random_range(1..6) {
        if v.is_empty() {
            v.extend_from_slice(TOKENS[rng.random_range(0..TOKENS.len())]);
            continue;
        }
        let at = rng.random_range(0..v.len());
        match rng.random_range(0..4) {
            0 => v[at] ^= 1 << rng.random_range(0..8),
            1 => {
                let end = (at + rng.random_range(1..16)).min(v.len());
                v.drain(at..end);
            }
            2 => {
                let end = (at + rng.random_range(1..32)).min(v.len());
                let chunk = v[at..end].to_vec();
                v.splice(at..at, chunk);
            }
            _ => {
                let t = TOKENS[rng.random_range(0..TOKENS.len())];
                v.splice(at..at, t.iter().copied());
            }
        }
    }
    v
}

#[test]
fn experiment_parser_never_panics() {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed(2026));
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments");
    let sources: Vec<String> = [
        "quickstart",
        "harada2012",
        "cluster-grid",
        "cis5650-scaling",
    ]
    .iter()
    .map(|n| std::fs::read_to_string(dir.join(format!("{n}.ron"))).unwrap())
    .collect();
    let (mut ok, mut err) = (0, 0);
    for i in 0..cases() {
        let src = &sources[i % sources.len()];
        let bytes = mutate(&mut rng, src.as_bytes());
        let text = String::from_utf8_lossy(&bytes).into_owned();
        match catch_unwind(AssertUnwindSafe(|| {
            Experiment::parse(&text, Path::new("fuzz.ron"))
        })) {
            Ok(Ok(e)) => {
                ok += 1;
                // A file that parses must also expand without panicking.
                let _ = e.cells();
            }
            Ok(Err(_)) => err += 1,
            Err(_) => panic!("the parser panicked on case {i}:\n{text}"),
        }
    }
    println!("{ok} mutated files parsed, {err} rejected");
    assert!(err > 0);
}

#[test]
fn gltf_importer_never_panics() {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed(7));
    let models = Path::new("/usr/share/assimp/models/glTF2");
    assert!(
        models.exists(),
        "install assimp-testmodels (as .ci/run does)"
    );
    let files = [
        "BoxTextured-glTF-Embedded/BoxTextured.gltf",
        "IndexOutOfRange/IndexOutOfRange.gltf",
        "BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb",
    ];
    let tmp = tempfile::tempdir().unwrap();
    // The external buffer that the mutated IndexOutOfRange.gltf names.
    {
        let f = "IndexOutOfRange/IndexOutOfRange.bin";
        std::fs::copy(
            models.join(f),
            tmp.path().join(Path::new(f).file_name().unwrap()),
        )
        .unwrap();
    }
    let sources: Vec<(String, Vec<u8>)> = files
        .iter()
        .map(|f| {
            (
                Path::new(f)
                    .extension()
                    .unwrap()
                    .to_string_lossy()
                    .into_owned(),
                std::fs::read(models.join(f)).unwrap(),
            )
        })
        .collect();
    let (mut ok, mut err) = (0, 0);
    for i in 0..cases() / 2 {
        let (ext, src) = &sources[i % sources.len()];
        let bytes = mutate(&mut rng, src);
        let path = tmp.path().join(format!("case.{ext}"));
        std::fs::write(&path, &bytes).unwrap();
        match catch_unwind(AssertUnwindSafe(|| load(&path, &GltfOptions::default()))) {
            Ok(Ok(_)) => ok += 1,
            Ok(Err(_)) => err += 1,
            Err(_) => {
                let keep = std::env::temp_dir().join(format!("gltf-fuzz-panic.{ext}"));
                std::fs::write(&keep, &bytes).unwrap();
                panic!(
                    "the glTF importer panicked on case {i}; input kept at {}",
                    keep.display()
                );
            }
        }
    }
    println!("{ok} mutated glTF files imported, {err} rejected");
    assert!(err > 0);
}

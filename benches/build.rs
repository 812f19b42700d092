//! Under the `cpp-peers` feature: compiles tinybvh's header (shipped in the tinybvh-rs crate,
//! found through `cargo metadata`) with benches/cpp/tinybvh_peer.cpp into a static library.
//! Without the feature it does nothing, so the default build needs no C++ toolchain.

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    #[cfg(feature = "cpp-peers")]
    tinybvh::compile();
}

#[cfg(feature = "cpp-peers")]
mod tinybvh {
    use std::path::PathBuf;
    use std::process::Command;

    /// The directory of tinybvh-rs's `tiny_bvh.h`, from the resolved dependency graph (so a
    /// vendored or patched source is found as well as the registry's).
    fn header_dir() -> PathBuf {
        let manifest = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
        let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let target = std::env::var("TARGET").expect("cargo sets TARGET");
        // Offline and for this target only: the build has fetched every package it needs, and
        // other platforms' packages need not be on the machine.
        let out = Command::new(cargo)
            .args([
                "metadata",
                "--format-version",
                "1",
                "--offline",
                "--features",
                "cpp-peers",
                "--filter-platform",
            ])
            .arg(target)
            .arg("--manifest-path")
            .arg(PathBuf::from(&manifest).join("Cargo.toml"))
            .output()
            .expect("cargo metadata runs");
        assert!(
            out.status.success(),
            "cargo metadata failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let meta: serde_json::Value =
            serde_json::from_slice(&out.stdout).expect("cargo metadata prints JSON");
        let pkg = meta["packages"]
            .as_array()
            .and_then(|p| p.iter().find(|p| p["name"] == "tinybvh-rs"))
            .expect("tinybvh-rs is a dependency under cpp-peers");
        let path = PathBuf::from(pkg["manifest_path"].as_str().expect("a manifest path"));
        path.parent()
            .expect("the manifest's directory")
            .join("ffi/tinybvh")
    }

    pub fn compile() {
        let dir = header_dir();
        assert!(
            dir.join("tiny_bvh.h").is_file(),
            "no tiny_bvh.h in {}",
            dir.display()
        );
        println!("cargo:rerun-if-changed=cpp/tinybvh_peer.cpp");
        cc::Build::new()
            .cpp(true)
            .std("c++20")
            .file("cpp/tinybvh_peer.cpp")
            .include(&dir)
            // tinybvh's BVH8_CPU kernels need AVX2 and FMA; the header picks its SIMD paths from
            // the compiler's target, as its own build (and the measurement) does.
            .flag("-march=native")
            .opt_level(3)
            // The header's own diagnostics, not ours.
            .warnings(false)
            .compile("rdbvh_tinybvh_peer");
    }
}

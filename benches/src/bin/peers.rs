//! `peers SCENE.obj [--json] [--wall]`: rdbvh beside obvhs 0.4, bvh 0.13 and parry3d 0.31 (and,
//! built with `--features cpp-peers`, Embree 3 and tinybvh, each by its default and by its
//! spatial-split build: `embree`, `embree-high`, `tinybvh`, `tinybvh8-hq`) on the same triangles
//! and rays (see `rdbvh_benches::compare`). Bad input prints one `error: ...` line and exits with
//! status 1; a peer that cannot be measured on the scene is left out, with a
//! `warning: left out: NAME: why` line on stderr under `--json` (a line of the text report
//! otherwise).

use std::process::ExitCode;

use rdbvh_benches::compare::{main_with, Options};

fn main() -> ExitCode {
    match main_with(std::env::args().skip(1), Options::default()) {
        Ok(out) => {
            print!("{out}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {}", e.replace('\n', " "));
            ExitCode::FAILURE
        }
    }
}

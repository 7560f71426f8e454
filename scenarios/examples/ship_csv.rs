//! Writes the paper's synthetic ship data as CSV files, to try the command line on:
//!
//! ```sh
//! cargo run -p leeway-scenarios --example ship_csv -- DIR [N] [WIND] [SEED]
//! leeway estimate examples/models/ship.som --data DIR/estimation.csv --method iv3
//! ```
//!
//! `DIR/estimation.csv`: one estimation experiment of the study (current mean
//! `[0.2, 0.2]`, wind mean `[WIND, WIND]` measured by an anemometer, noisy
//! states and heading; default N = 5000, WIND = 1, SEED = 1).
//! `DIR/validation.csv`: a zigzag validation run of 1000 samples on the same
//! day — the same current and wind, noisy measurements (seed `SEED + 1`) — so
//! that `leeway validate` with the estimate holds the current it found.

use leeway_data::write_csv;
use leeway_model::Interpreter;
use leeway_scenarios::study;
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let dir = PathBuf::from(
        args.first()
            .ok_or("usage: ship_csv DIR [N] [WIND] [SEED]")?,
    );
    let n: usize = args.get(1).map_or(Ok(5000), |s| s.parse())?;
    let wind: f64 = args.get(2).map_or(Ok(1.0), |s| s.parse())?;
    let seed: u64 = args.get(3).map_or(Ok(1), |s| s.parse())?;
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/models/ship.som");
    let c = leeway_structure::compile(&std::fs::read_to_string(path)?, &Default::default());
    let ir = c.ir.ok_or("ship.som does not compile")?;
    let model = Interpreter::new(ir.clone());
    let (e, _) =
        study::estimation_experiment(&model, &study::InputDesign::default(), wind, n, seed);
    let val = leeway_scenarios::synth::experiment(
        &model,
        &study::true_system(wind),
        "validation",
        &[4.0, 0.0, 0.0],
        0.0,
        &study::validation_input(1000),
        seed + 1,
    )
    .0;
    std::fs::create_dir_all(&dir)?;
    for (name, exp) in [("estimation.csv", &e), ("validation.csv", &val)] {
        let mut file = std::io::BufWriter::new(std::fs::File::create(dir.join(name))?);
        write_csv(&ir, &[exp], 0.0, &mut file)?;
        println!("wrote {}", dir.join(name).display());
    }
    Ok(())
}

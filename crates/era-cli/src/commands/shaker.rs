//! `era simulate shaker`: a shaker test of a seeded structure in the time domain, written
//! as a time-history CSV with the truth beside it.

use crate::config::Shaker;
use crate::output::report::{finish_output, Human};
use crate::output::simulate::{shaker_truth, write_shaker};
use std::time::Instant;

pub fn run(a: &Shaker) -> anyhow::Result<()> {
    let settings = a.settings;
    let human = Human::new(&settings);
    let test = crate::config::shaker::test(a)?;
    let clock = Instant::now();
    let record = era::sim::shaker::simulate_shaker_test(&test).map_err(|e| {
        crate::work::flag_error(e, |name, _| {
            Some((format!("--{}", name.replace('_', "-")), ""))
        })
    })?;
    let simulate_s = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    let outputs_columns = format!("{}-{}", a.inputs + 1, a.inputs + a.outputs);
    let summary = shaker_truth(a, &record, test.excitation, test.quantity, &outputs_columns);
    let truth_path = write_shaker(a, &record, &test, &summary)?;
    human.print(&format!(
        "wrote {} ({} samples at {} Hz: force1-{} then {} outputs, columns {}) and {}\n",
        a.out.display(),
        record.outputs[0].len(),
        a.sample_rate,
        a.inputs,
        a.outputs,
        outputs_columns,
        truth_path.display()
    ));
    finish_output(
        &human,
        &settings,
        summary,
        &[
            ("simulate", simulate_s),
            ("write", clock.elapsed().as_secs_f64()),
        ],
    )
}

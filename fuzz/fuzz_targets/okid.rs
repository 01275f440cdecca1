//! OKID on arbitrary records: any number of samples, NaN and inf, constant or
//! dependent inputs, huge values, every observer setting. OKID must return a model's
//! Markov parameters or an error, never panic, hang or allocate without bound.
#![no_main]
use era::sources::okid::{okid, ObserverOrder, OkidOptions, Record};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&head, rest)) = data.split_first() else {
        return;
    };
    let inputs = 1 + usize::from(head & 1);
    let outputs = 1 + usize::from((head >> 1) & 3);
    let order = 1 + usize::from((head >> 3) & 7);
    let channels = inputs + outputs;
    // Two bytes a sample; a few codes stand for the values a bad file holds.
    let values: Vec<f64> = rest
        .chunks_exact(2)
        .map(|c| match i16::from_le_bytes([c[0], c[1]]) {
            i16::MAX => f64::NAN,
            i16::MIN => f64::INFINITY,
            32766 => 1e300,
            -32767 => 1e-300,
            v => f64::from(v),
        })
        .collect();
    let samples = values.len() / channels;
    if samples == 0 {
        return;
    }
    let columns: Vec<&[f64]> = values.chunks_exact(samples).take(channels).collect();
    let record = Record {
        inputs: &columns[..inputs],
        outputs: &columns[inputs..],
    };
    let mut options = OkidOptions::default();
    options.observer_order = if head & 0x40 != 0 {
        ObserverOrder::Fixed(order)
    } else {
        ObserverOrder::Auto {
            max: Some(2 * order),
        }
    };
    options.markov_samples = 64;
    options.gain = head & 0x80 != 0;
    let _ = okid(&[record, record], &options);
});

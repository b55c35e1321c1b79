//! A record's outputs as its users read them: an output the model holds at zero (a load
//! voltage without a transducer) keeps no samples in the record, and reads as zeros.

use std::borrow::Cow;

use super::Record;

impl Record {
    /// The samples of output `i` (0 for `v1_v`, 1 for `v2_v`, then `more_v`): zeros for an
    /// output the model holds at zero, whose samples the record does not keep; empty for an
    /// output the model does not have.
    pub fn output_samples(&self, i: usize) -> Cow<'_, [f64]> {
        if i >= self.outputs.len() {
            return (&[][..]).into();
        }
        let kept = match i {
            0 => &self.v1_v[..],
            1 => &self.v2_v[..],
            _ => self.more_v.get(i - 2).map_or(&[][..], |v| &v[..]),
        };
        if self.keeps(i, kept) {
            kept.into()
        } else {
            vec![0.0; self.samples].into()
        }
    }

    /// Whether `kept`, the record's vector of output `i`, holds that output's samples: it does
    /// unless the model has the output and holds it at zero, when the vector stays empty.
    pub(super) fn keeps(&self, i: usize, kept: &[f64]) -> bool {
        kept.len() == self.samples || i >= self.outputs.len()
    }

    /// The first two outputs' samples ([`Record::output_samples`] of 0 and 1), taken out of
    /// the record: its own vectors where it keeps them, zeros for an output the model holds at
    /// zero.
    pub fn take_pair(&mut self) -> [Vec<f64>; 2] {
        let n = self.samples;
        let keeps = [self.keeps(0, &self.v1_v), self.keeps(1, &self.v2_v)];
        let take = |v: &mut Vec<f64>, kept: bool| {
            if kept {
                std::mem::take(v)
            } else {
                vec![0.0; n]
            }
        };
        [
            take(&mut self.v1_v, keeps[0]),
            take(&mut self.v2_v, keeps[1]),
        ]
    }
}

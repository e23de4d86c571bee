//! The defects of measured data a case accepts by leaving values out
//! (`mask`).

/// A kind of defect in measured data that a case accepts by leaving the
/// affected values out (`[measurement] mask = [...]`), instead of refusing
/// the file. What is left out is reported.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum MaskRule {
    /// `non-finite`: a frequency line where any channel's value is NaN or
    /// infinite is left out, for every channel.
    NonFinite,
    /// `duplicate-lines`: a line that repeats the frequency of the line
    /// before it is left out (the first is kept). Lines that go backwards
    /// are still refused.
    DuplicateLines,
    /// `unmodelled-channels`: a channel whose response or reference is at a
    /// node the model lacks, or at a DOF it holds fixed, is left out.
    UnmodelledChannels,
    /// `bad-coherence`: a coherence record with a value outside 0..1 (or
    /// not a number) is left out; its channel is weighted as if its
    /// coherence were 1.
    BadCoherence,
}

impl MaskRule {
    /// Every rule, in the order of the documentation.
    pub const ALL: [MaskRule; 4] =
        [MaskRule::NonFinite, MaskRule::DuplicateLines, MaskRule::UnmodelledChannels, MaskRule::BadCoherence];

    /// The name used in case files.
    pub fn name(self) -> &'static str {
        match self {
            MaskRule::NonFinite => "non-finite",
            MaskRule::DuplicateLines => "duplicate-lines",
            MaskRule::UnmodelledChannels => "unmodelled-channels",
            MaskRule::BadCoherence => "bad-coherence",
        }
    }

    /// The rule of a case-file name.
    pub fn parse(name: &str) -> Option<MaskRule> {
        MaskRule::ALL.into_iter().find(|r| r.name() == name.trim())
    }
}

impl std::fmt::Display for MaskRule {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

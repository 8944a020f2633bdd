//! Fingerprints of scenes and graphs, which checkpoints and shards carry to recognise a
//! mismatch.

/// FNV-1a, 64 bits: fingerprints of scenes and graphs (not for security, for recognising a
/// mismatch).
#[derive(Debug, Clone, Copy)]
pub struct Fnv(u64);

impl Default for Fnv {
    fn default() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    pub fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= b as u64;
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }

    pub fn finish(&self) -> u64 {
        self.0
    }
}

/// Fingerprint of a graph file's text with comments and blank space removed, so that a
/// reformatted or recommented graph is the same graph and any other change is not.
pub fn graph_fingerprint(text: &str) -> u64 {
    let mut hash = Fnv::default();
    for line in text.lines() {
        let code = line.split("//").next().unwrap_or("");
        let compact: String = code.chars().filter(|c| !c.is_whitespace()).collect();
        hash.write(compact.as_bytes());
    }
    hash.finish()
}

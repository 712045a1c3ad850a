//! The mutator: a seeded generator of malformed variants of valid inputs. Each case stacks one
//! to eight edits (bit flips, interesting integers, cut, inserted, repeated or spliced ranges,
//! dictionary words) on a corpus entry, so most cases stay close enough to the format to get
//! past its first checks.

/// splitmix64: small, fast and reproducible from one seed.
pub struct Rng(u64);

impl Rng {
    /// A generator from `seed`.
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }

    /// The next 64 random bits.
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `0..n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    /// A length that is usually short: 1 to 8, sometimes up to 256.
    fn len(&mut self) -> usize {
        if self.below(4) == 0 { 1 + self.below(256) } else { 1 + self.below(8) }
    }
}

/// Integers at the edges of what formats store: sizes, counts, offsets.
const INTERESTING: [u64; 14] =
    [0, 1, 2, 0x7f, 0x80, 0xff, 0x7fff, 0xffff, 0x7fff_ffff, 0x8000_0000, 0xffff_ffff, 1 << 32, 0x7fff_ffff_ffff_ffff, u64::MAX];

/// `base` with one to eight edits; `splice` is another corpus entry to copy ranges from and
/// `words` the target's dictionary.
pub fn mutate(rng: &mut Rng, base: &[u8], splice: &[u8], words: &[&[u8]]) -> Vec<u8> {
    let mut v = base.to_vec();
    for _ in 0..1 + rng.below(8) {
        edit(rng, &mut v, splice, words);
    }
    v
}

fn edit(rng: &mut Rng, v: &mut Vec<u8>, splice: &[u8], words: &[&[u8]]) {
    let at = |rng: &mut Rng, v: &Vec<u8>| if v.is_empty() { 0 } else { rng.below(v.len()) };
    match rng.below(11) {
        0 if !v.is_empty() => {
            let i = at(rng, v);
            v[i] ^= 1 << rng.below(8);
        }
        1 if !v.is_empty() => {
            let i = at(rng, v);
            v[i] = rng.next() as u8;
        }
        2 | 3 if !v.is_empty() => {
            // An interesting integer, 1 to 8 bytes wide, either byte order.
            let width = [1, 2, 4, 8][rng.below(4)];
            let x = INTERESTING[rng.below(INTERESTING.len())].wrapping_add((rng.below(3) as u64).wrapping_sub(1));
            let bytes = if rng.below(2) == 0 { x.to_le_bytes() } else { x.to_be_bytes() };
            let bytes = if rng.below(2) == 0 { &bytes[..width] } else { &bytes[8 - width..] };
            let i = at(rng, v);
            for (k, b) in bytes.iter().enumerate() {
                if let Some(slot) = v.get_mut(i + k) {
                    *slot = *b;
                }
            }
        }
        4 if !v.is_empty() => {
            let i = at(rng, v);
            let n = rng.len().min(v.len() - i);
            v.drain(i..i + n);
        }
        5 => {
            let i = at(rng, v);
            let bytes: Vec<u8> = (0..rng.len()).map(|_| rng.next() as u8).collect();
            v.splice(i..i, bytes);
        }
        6 if !v.is_empty() => {
            // Repeat a range.
            let i = at(rng, v);
            let n = rng.len().min(v.len() - i);
            let chunk = v[i..i + n].to_vec();
            let j = at(rng, v);
            v.splice(j..j, chunk);
        }
        7 if !splice.is_empty() => {
            // Overwrite with a range of another entry from the same offset: a header from one,
            // a body from the other.
            let i = rng.below(splice.len());
            let n = rng.len().min(splice.len() - i);
            for k in 0..n {
                if let Some(slot) = v.get_mut(i + k) {
                    *slot = splice[i + k];
                }
            }
        }
        8 | 9 if !words.is_empty() => {
            let w = words[rng.below(words.len())];
            let i = at(rng, v);
            if rng.below(2) == 0 {
                v.splice(i..i, w.iter().copied());
            } else {
                let end = (i + w.len()).min(v.len());
                v.splice(i..end, w.iter().copied());
            }
        }
        10 if !v.is_empty() => {
            let n = rng.below(v.len());
            v.truncate(n);
        }
        _ => {
            let i = at(rng, v);
            v.insert(i, rng.next() as u8);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_seed_reproduces_its_cases_and_cases_differ() {
        let base = b"color_0000.exr and some more bytes to edit".to_vec();
        let words: &[&[u8]] = &[b"Vector", b"4294967296"];
        let cases = |seed| {
            let mut rng = Rng::new(seed);
            (0..50).map(|_| mutate(&mut rng, &base, b"other", words)).collect::<Vec<_>>()
        };
        assert_eq!(cases(7), cases(7));
        let distinct: std::collections::HashSet<_> = cases(7).into_iter().collect();
        assert!(distinct.len() > 40, "{} distinct of 50", distinct.len());
        assert!(distinct.iter().any(|c| c != &base && c.len() == base.len()), "some edit keeps the length");
        assert!(distinct.iter().any(|c| c.windows(6).any(|w| w == b"Vector")), "dictionary words go in");
    }
}

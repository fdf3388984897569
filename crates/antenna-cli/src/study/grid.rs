//! Shards of a study's grid, for a cluster's array jobs: `--shard i/n` runs the grid points
//! whose index is `i - 1` modulo `n` (interleaved, so that every shard gets a share of each
//! axis value and the shards take about as long). The union of the `n` shards is the grid,
//! each point exactly once.

use std::fmt;
use std::str::FromStr;

/// Shard `index` (1-based) of `count`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// Which shard, `1..=count`.
    pub index: usize,
    /// How many shards.
    pub count: usize,
}

impl Shard {
    /// The whole grid: shard 1 of 1.
    pub const ALL: Shard = Shard { index: 1, count: 1 };

    /// Whether grid point `grid_index` belongs to this shard.
    pub fn contains(&self, grid_index: usize) -> bool {
        grid_index % self.count == self.index - 1
    }

    /// The grid points of this shard, for a grid of `len` points, in increasing order.
    pub fn indices(&self, len: usize) -> impl Iterator<Item = usize> + use<> {
        (self.index - 1..len).step_by(self.count)
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl FromStr for Shard {
    type Err = String;

    /// `"i/n"` with `1 <= i <= n`.
    fn from_str(s: &str) -> Result<Shard, String> {
        let bad = || format!("shard \"{s}\": expected i/n with 1 <= i <= n, e.g. 2/8");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let index: usize = i.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if index == 0 || index > count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_partition_the_grid() {
        for len in [0, 1, 7, 24, 25] {
            for count in 1..=9 {
                let mut seen = vec![0; len];
                for index in 1..=count {
                    let shard = Shard { index, count };
                    for i in shard.indices(len) {
                        assert!(shard.contains(i));
                        seen[i] += 1;
                    }
                }
                assert!(seen.iter().all(|&c| c == 1), "len {len}, {count} shards");
            }
        }
    }

    #[test]
    fn shards_parse_one_based() {
        assert_eq!("2/8".parse(), Ok(Shard { index: 2, count: 8 }));
        assert_eq!(" 1 / 1 ".parse(), Ok(Shard::ALL));
        for bad in ["0/4", "5/4", "1", "a/b", "1/0", "-1/2"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }
}

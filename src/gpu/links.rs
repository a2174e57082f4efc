//! Link records beyond one storage buffer's range: the records stay in one buffer (its size is
//! bounded by memory, not by `maxStorageBufferRange`), and the global pass reads it through one
//! descriptor per chunk of at most that range, drawing each chunk's lines with the chunk's set
//! bound. Pure: the chunking and the split of the draws are device-free and tested here.
//!
//! The paper's layout, links as vertex buffers read through vertex input attributes, has no
//! range limit either; it was measured against pulling records by vertex index (README,
//! "Where lavapipe spends an iteration": instanced attributes cost 480–586 ms of front end per
//! Cornell iteration against 387–436 ms pulled, the wall time equal), and per-vertex attributes
//! without instances would store every record twice. Chunked descriptors keep the pulled
//! records and cost one descriptor-set bind per chunk.

use super::layout::GpuLink;

/// Bytes of one link record.
const RECORD: u64 = std::mem::size_of::<GpuLink>() as u64;

/// Records per chunk are a multiple of this, so that every chunk's offset (a multiple of
/// 12 · 256 = 3072 bytes) meets any `minStorageBufferOffsetAlignment` (at most 256 bytes).
const ALIGN_RECORDS: u64 = 256;

/// How the link records are split into descriptor ranges.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LinkChunks {
    /// Records one descriptor covers (the last chunk may hold fewer).
    pub per_chunk: u32,
    /// Descriptor ranges (at least one).
    pub chunks: u32,
    /// Records in the buffer.
    pub records: u64,
}

impl LinkChunks {
    /// Chunks for `records` link records read through descriptors of at most `range` bytes.
    pub fn new(records: u64, range: u64) -> Self {
        let per_chunk = ((range / RECORD) / ALIGN_RECORDS * ALIGN_RECORDS).clamp(
            ALIGN_RECORDS,
            u32::MAX as u64 / 2 / ALIGN_RECORDS * ALIGN_RECORDS,
        );
        let records = records.max(1);
        Self {
            per_chunk: per_chunk as u32,
            chunks: records.div_ceil(per_chunk) as u32,
            records,
        }
    }

    /// Offset and size in bytes of chunk `c`'s descriptor range.
    pub fn range(&self, c: u32) -> (u64, u64) {
        let first = c as u64 * self.per_chunk as u64;
        let count = (self.records - first).min(self.per_chunk as u64);
        (first * RECORD, count * RECORD)
    }

    /// Splits the draw buckets `(sender, line width, first record, records)` at chunk
    /// boundaries, in their order (so blending sums in the same order as one buffer would).
    pub fn pieces(&self, buckets: &[(u32, u32, u32, u32)]) -> Vec<LinkDraw> {
        let per = self.per_chunk as u64;
        let mut out = Vec::with_capacity(buckets.len());
        for &(sender, width, first, count) in buckets {
            let (mut first, end) = (first as u64, first as u64 + count as u64);
            while first < end {
                let chunk = first / per;
                let stop = end.min((chunk + 1) * per);
                out.push(LinkDraw {
                    chunk: chunk as u32,
                    sender,
                    width,
                    first: (first - chunk * per) as u32,
                    count: (stop - first) as u32,
                });
                first = stop;
            }
        }
        out
    }
}

/// One draw of the global pass: `count` records from `first` within chunk `chunk`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LinkDraw {
    /// Descriptor range whose set is bound.
    pub chunk: u32,
    /// Image the senders' I_ex is read from.
    pub sender: u32,
    /// Line width.
    pub width: u32,
    /// First record, counted from the chunk's start.
    pub first: u32,
    /// Records.
    pub count: u32,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_chunk_when_the_range_holds_every_record() {
        let c = LinkChunks::new(1000, 128 << 20);
        assert_eq!(c.chunks, 1);
        assert_eq!(c.range(0), (0, 12_000));
        let buckets = [(0, 2, 0, 600), (1, 3, 600, 400)];
        let p = c.pieces(&buckets);
        assert_eq!(p.len(), 2);
        assert_eq!((p[1].chunk, p[1].first, p[1].count), (0, 600, 400));
    }

    #[test]
    fn chunks_cover_every_record_once_at_aligned_offsets() {
        // 256 records per chunk (3072 bytes), 1000 records: 4 chunks, the last of 232.
        let c = LinkChunks::new(1000, 4000);
        assert_eq!((c.per_chunk, c.chunks), (256, 4));
        assert_eq!(c.range(3), (768 * 12, 232 * 12));
        for k in 0..c.chunks {
            assert_eq!(c.range(k).0 % 256, 0);
            assert!(c.range(k).1 <= 4000);
        }
        let buckets = [(0, 1, 0, 300), (2, 4, 300, 500), (1, 1, 800, 200)];
        let p = c.pieces(&buckets);
        let mut seen = vec![0u32; 1000];
        for d in &p {
            assert!(d.first + d.count <= c.per_chunk);
            for r in d.first..d.first + d.count {
                seen[(d.chunk * c.per_chunk + r) as usize] += 1;
            }
        }
        assert!(seen.iter().all(|&n| n == 1));
        // Order and bucket attributes kept: 300 → 256 + 44; 500 → 212 + 256 + 32; 200.
        let counts: Vec<u32> = p.iter().map(|d| d.count).collect();
        assert_eq!(counts, vec![256, 44, 212, 256, 32, 200]);
        assert_eq!((p[2].sender, p[2].width), (2, 4));
    }

    #[test]
    fn no_records_still_make_one_chunk() {
        let c = LinkChunks::new(0, 1 << 20);
        assert_eq!((c.chunks, c.records), (1, 1));
        assert!(c.pieces(&[]).is_empty());
    }
}

//! A quick hash of `f64` values' bits, the filter before a full comparison: the UMAT's
//! `STATEV` values against the state a point holds (`umat::statev_mode`), a core against
//! the steps of an increment (`share_table`).

/// A hash of `values`' bits (not cryptographic: a quick filter before a comparison).
/// Four independent lanes, one per value mod 4, so that the multiplications overlap
/// (one chain was a serial dependency over the 790 values of a member's point).
pub(crate) fn values_hash(values: &[f64]) -> u64 {
    const PRIME: u64 = 0x0100_0000_01b3;
    let mix = |h: u64, bits: u64| (h.rotate_left(5) ^ bits).wrapping_mul(PRIME);
    let mut lanes = [
        0xcbf2_9ce4_8422_2325,
        0x9e37_79b9_7f4a_7c15,
        0x2545_f491_4f6c_dd1d,
        0x8422_2325_cbf2_9ce4,
    ];
    let mut quads = values.chunks_exact(4);
    for quad in &mut quads {
        for (lane, v) in lanes.iter_mut().zip(quad) {
            *lane = mix(*lane, v.to_bits());
        }
    }
    for (lane, v) in lanes.iter_mut().zip(quads.remainder()) {
        *lane = mix(*lane, v.to_bits());
    }
    lanes
        .iter()
        .fold(values.len() as u64, |h, &lane| mix(h, lane))
}

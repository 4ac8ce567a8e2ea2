//! The last few answers of an expensive computation, by what they depend on: the calibrations
//! of a page's teach cuts ([`super::teach_cuts`]), the references of its scenarios
//! ([`super::savings`]).

/// Puts `value` under `key` as the newest of `entries` (newest last), dropping an older entry
/// of the same key and the oldest beyond `keep`.
pub fn remember<K: PartialEq, V>(entries: &mut Vec<(K, V)>, key: K, value: V, keep: usize) {
    entries.retain(|(k, _)| *k != key);
    entries.push((key, value));
    let excess = entries.len().saturating_sub(keep);
    entries.drain(..excess);
}

/// The value under `key`, if `entries` hold it.
pub fn find<'a, K: PartialEq, V>(entries: &'a [(K, V)], key: &K) -> Option<&'a V> {
    entries.iter().find(|(k, _)| k == key).map(|(_, v)| v)
}

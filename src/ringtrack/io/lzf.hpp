#pragma once
/// LZF compression as used by PCD "binary_compressed" (the liblzf stream format, own code).

#include <cstdint>
#include <span>
#include <vector>

namespace ringtrack::io {

/// Most bytes one stream byte can decode to: the longest back reference, 3 bytes, copies 264.
/// A declared size above kLzfMaxExpansion times the stream's size cannot be genuine.
inline constexpr std::size_t kLzfMaxExpansion = 88;

/// Compresses bytes into an LZF stream: literal runs of 1-32 bytes (control byte 0-31) and back
/// references of 3-264 bytes up to 8192 bytes back. Never fails; incompressible data grows by
/// 1/32 (one control byte per 32 literals).
std::vector<std::uint8_t> lzf_compress(std::span<const std::uint8_t> in);

/// Decompresses an LZF stream that must decode to exactly out.size() bytes; throws
/// core::InputError ("lzf: ... at stream offset N") on a corrupt or mis-sized stream.
void lzf_decompress(std::span<const std::uint8_t> in, std::span<std::uint8_t> out);

}  // namespace ringtrack::io

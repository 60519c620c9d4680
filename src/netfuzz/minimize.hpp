// Delta debugging (ddmin) over a case's steps: the smallest sequence that still makes the
// same oracle fire. A single send holding several frames is first cut into one step per
// frame, so coalesced bursts shrink to the frame that matters; then each remaining frame's
// PDU is cut to the shortest tail that still fires (the MBAP length, or the RTU CRC and the
// ASCII LRC, kept consistent). Frames a conforming reader discards (bad CRC, broken on purpose)
// are left whole.
#pragma once

#include <functional>

#include "codec/framing.hpp"
#include "netfuzz/case.hpp"

namespace mbstorm::netfuzz {

// `reproduces` runs a candidate against the target. At most `budget` runs. Without
// `byte_level` only whole frames and steps are dropped (for crashes and hangs, where every try
// costs a restart or a timeout).
Case minimize_case(const Case& original, const std::function<bool(const Case&)>& reproduces,
                   unsigned budget, bool byte_level = true,
                   codec::Framing framing = codec::Framing::Mbap);

// One step per complete frame for sends that hold several (others unchanged).
Case split_frames(const Case& c, codec::Framing framing = codec::Framing::Mbap);

}  // namespace mbstorm::netfuzz

// libFuzzer target for the wire decoders and the receiver's set algebra (long runs beyond the
// fixed-seed CI test). Build: see protocol/CMakeLists.txt (OCC_LIBFUZZER).
// Properties: nothing crashes or trips a sanitizer; an accepted frame re-encodes to the same
// bytes; a stream of frames is decoded frame by frame, NodeDiff/EndOfFrame feed a receiver.
#include <cstdlib>

#include "protocol/visible_set.hpp"
#include "protocol/wire.hpp"

using namespace occ;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::span<const uint8_t> input(data, size);
  if (auto m = wire::decode(input)) {
    const auto again = wire::encode(*m);
    if (!std::equal(again.begin(), again.end(), input.begin(), input.end())) std::abort();
  }
  VisibleSet set(4096);
  DiffReceiver rx;
  for (size_t pos = 0; pos < size;) {
    auto h = wire::decode_header(input.subspan(pos));
    if (!h || size - pos - wire::kHeaderBytes < h->payload_bytes) break;
    const auto payload = input.subspan(pos + wire::kHeaderBytes, h->payload_bytes);
    auto m = wire::decode_payload(h->type, payload);
    if (!m) break;
    if (auto* d = std::get_if<wire::NodeDiff>(&*m)) (void)rx.on_diff(set, *d);
    if (auto* e = std::get_if<wire::EndOfFrame>(&*m)) (void)rx.on_end_of_frame(set, *e);
    if (set.hash() != set_hash(set.ids())) std::abort();
    pos += wire::kHeaderBytes + h->payload_bytes;
  }
  return 0;
}

// SPDX-License-Identifier: MIT
// The messages a page sends to `harap view`'s server: any bytes, parsed and validated against a
// small session (100 vertices, 3 handle groups), and as the query of the page's WebSocket address.
// A bad message must be an InputError (the page gets it as an error message; a bad query is
// refused with it), never a crash or another exception.
#include "tests/fuzz/fuzz_target.h"
#include "view/protocol.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text = harap::fuzzing::AsText(data, size);
  harap::view::MessageLimits limits;
  limits.num_vertices = 100;
  limits.num_groups = 3;
  limits.num_levels = 4;
  try {
    const harap::view::ParsedMessage parsed = harap::view::ParseClientMessage(text, limits);
    if (const auto* add = std::get_if<harap::view::AddHandleMessage>(&parsed.message)) {
      HARAP_CHECK(add->vertex >= 0 && add->vertex < limits.num_vertices, "vertex in range");
    }
    if (const auto* move = std::get_if<harap::view::MoveMessage>(&parsed.message)) {
      HARAP_CHECK(move->group >= 0 && move->group < limits.num_groups, "group in range");
      HARAP_CHECK(move->rotation.allFinite() && move->translation.allFinite(), "finite move");
    }
    if (const auto* level = std::get_if<harap::view::LevelMessage>(&parsed.message)) {
      HARAP_CHECK(level->level >= 0 && level->level < limits.num_levels, "level in range");
    }
  } catch (const harap::InputError&) {
    // The expected answer to a malformed message.
  }
  // The same bytes as the query of the page's WebSocket address.
  try {
    const harap::view::PageOptions options = harap::view::ParsePageQuery(text);
    HARAP_CHECK(options.display_vertices == 0 ||
                    options.display_vertices >= harap::view::kMinDisplayVertices,
                "display budget in range");
  } catch (const harap::InputError&) {
  }
  (void)harap::view::MessageIdOf(text);
  (void)harap::view::BinaryMessageRefusal(size);
  return 0;
}

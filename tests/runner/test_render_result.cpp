// The renderer's failures as the harness's Error (harness/render_result.hpp):
// the kind decides the exit code a person sees, the message says what was
// being done.
#include "curvlab/harness/render_result.hpp"

#include <gtest/gtest.h>

#include <string>
#include <variant>

namespace {

using curvlab::harness::Error;
using curvlab::harness::from_renderer;
using curvlab::renderer::RenderError;

TEST(RenderResult, EachKindBecomesTheHarnessKindAPersonActsOn) {
  const struct {
    RenderError::Kind from;
    Error::Kind to;
    int exit_code;
  } cases[] = {
      {RenderError::Kind::device, Error::Kind::device, 1},
      {RenderError::Kind::surface, Error::Kind::device, 1},
      {RenderError::Kind::shader, Error::Kind::device, 1},
      {RenderError::Kind::font, Error::Kind::io, 1},
      {RenderError::Kind::file, Error::Kind::io, 1},
      {RenderError::Kind::stimulus, Error::Kind::bad_input, 2},
  };
  for (const auto& c : cases) {
    const Error e = from_renderer(RenderError{c.from, "what failed"}, "while starting: ");
    EXPECT_EQ(e.kind, c.to) << static_cast<int>(c.from);
    EXPECT_EQ(curvlab::harness::exit_code(e), c.exit_code) << static_cast<int>(c.from);
    EXPECT_EQ(e.message, "while starting: what failed");
  }
}

TEST(RenderResult, AValuePassesThrough) {
  const auto made = from_renderer(std::variant<int, RenderError>(7));
  ASSERT_TRUE(made.has_value());
  EXPECT_EQ(made.value(), 7);
  const auto failed = from_renderer(std::variant<int, RenderError>(RenderError{RenderError::Kind::file, "x.png"}));
  ASSERT_FALSE(failed.has_value());
  EXPECT_EQ(failed.error().kind, Error::Kind::io);
}

}  // namespace

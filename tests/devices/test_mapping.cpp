// Mapping-file errors name file:line:column, the field, and what was expected.
#include "curvlab/harness/devices/mapping.hpp"

#include <gtest/gtest.h>

namespace {

using namespace curvlab::harness::devices;

std::string error_of(const std::string& text) {
  auto r = parse_mapping(text, "pedals.toml");
  if (r) return "(parsed)";
  EXPECT_EQ(r.error().kind, curvlab::harness::Error::Kind::bad_input);
  return r.error().message;
}

TEST(MappingFile, SyntaxErrorNamesLineAndColumn) {
  EXPECT_EQ(error_of("[[device]]\nname = \"x\nvendor_id = 1\n").substr(0, 25),
            "pedals.toml:2:10: (syntax");
}

TEST(MappingFile, WrongTypeNamesTheField) {
  const std::string text =
      "[[device]]\nname = \"box\"\nvendor_id = \"0x1234\"\n"
      "[[device.binding]]\nresponse = \"a\"\nkind = \"bit\"\nbyte = 0\nbit = 0\n";
  EXPECT_EQ(error_of(text), "pedals.toml:3:13: device[0].vendor_id: expected an integer");
}

TEST(MappingFile, OutOfRangeBit) {
  const std::string text =
      "[[device]]\nname = \"box\"\nusage_page = 1\n"
      "[[device.binding]]\nresponse = \"a\"\nkind = \"bit\"\nbyte = 0\nbit = 8\n";
  EXPECT_EQ(error_of(text),
            "pedals.toml:8:7: device[0].binding[0].bit: expected an integer in 0 … 7, got 8");
}

TEST(MappingFile, UnknownKeyListsTheAllowedOnes) {
  const std::string text =
      "[[device]]\nname = \"box\"\nusage_page = 1\n"
      "[[device.binding]]\nresponse = \"a\"\nkind = \"bit\"\nbyte = 0\nbit = 1\nbite = 2\n";
  EXPECT_EQ(error_of(text), "pedals.toml:9:8: device[0].binding[0].bite: unknown key "
                            "(expected one of: bit, byte, kind, response)");
}

TEST(MappingFile, MissingFieldsAndBadKinds) {
  EXPECT_EQ(error_of("[[device]]\nname = \"box\"\n[[device.binding]]\nresponse = \"a\"\n"
                     "kind = \"bit\"\nbit = 1\n"),
            "pedals.toml:1:1: device[0].vendor_id: missing: a device is matched by "
            "vendor_id/product_id and/or usage_page/usage (see `curvlab devices`)");
  EXPECT_EQ(error_of("[[device]]\nname = \"box\"\nusage = 5\n[[device.binding]]\n"
                     "response = \"a\"\nkind = \"bit\"\nbit = 1\n"),
            "pedals.toml:4:1: device[0].binding[0].byte: missing (expected an integer)");
  EXPECT_EQ(error_of("[[device]]\nname = \"box\"\nusage = 5\n[[device.binding]]\n"
                     "response = \"a\"\nkind = \"button\"\n"),
            "pedals.toml:6:8: device[0].binding[0].kind: expected \"bit\", \"key\" or \"axis\", "
            "got \"button\"");
  EXPECT_EQ(error_of("[[device]]\nname = \"box\"\nusage = 5\n"),
            "pedals.toml:1:1: device[0].binding: missing: add at least one [[device.binding]]");
  EXPECT_EQ(error_of("# nothing\n"), "pedals.toml:1:1: device: missing: add at least one [[device]] table");
}

TEST(MappingFile, AxisNeedsOneThresholdAndAReleaseOnTheRightSide) {
  const std::string head = "[[device]]\nname = \"pedal\"\nusage = 4\n[[device.binding]]\n"
                           "response = \"go\"\nkind = \"axis\"\nbyte = 1\n";
  EXPECT_NE(error_of(head).find("give exactly one of 'above' or 'below'"), std::string::npos);
  EXPECT_EQ(error_of(head + "above = 200\nrelease = 220\n"),
            "pedals.toml:9:11: device[0].binding[0].release: must be on the released side of "
            "'above' (≤ 200)");
  EXPECT_EQ(error_of(head + "bits = 12\nabove = 2\n"),
            "pedals.toml:8:8: device[0].binding[0].bits: expected 8 or 16");
}

TEST(MappingFile, MatchingByVendorProductOrUsage) {
  auto r = parse_mapping(
      "[[device]]\nname = \"pad\"\nvendor_id = 0x046d\nproduct_id = 0xc216\n"
      "[[device.binding]]\nresponse = \"a\"\nkind = \"bit\"\nbyte = 0\nbit = 0\n"
      "[[device]]\nname = \"any keyboard\"\nusage_page = 1\nusage = 6\n"
      "[[device.binding]]\nresponse = \"a\"\nkind = \"key\"\nkeycode = 4\n",
      "m.toml");
  const auto& file = r.value();
  HidDeviceInfo pad;
  pad.vendor_id = 0x046d;
  pad.product_id = 0xc216;
  pad.usage_page = 1;
  pad.usage = 5;
  HidDeviceInfo keyboard;
  keyboard.vendor_id = 0x1234;
  keyboard.usage_page = 1;
  keyboard.usage = 6;
  HidDeviceInfo mouse = keyboard;
  mouse.usage = 2;
  ASSERT_NE(file.find(pad), nullptr);
  EXPECT_EQ(file.find(pad)->name, "pad");
  ASSERT_NE(file.find(keyboard), nullptr);
  EXPECT_EQ(file.find(keyboard)->name, "any keyboard");
  EXPECT_EQ(file.find(mouse), nullptr);
}

TEST(MappingFile, MissingFileIsAnError) {
  auto r = load_mapping("/nonexistent/curvlab/map.toml");
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().kind, curvlab::harness::Error::Kind::not_found);
  EXPECT_EQ(r.error().message, "/nonexistent/curvlab/map.toml:0:0: (file): cannot be read");
}

}  // namespace

namespace {

using namespace curvlab::harness::devices;

// The mapping file goes through the same guard as protocol files: text that
// would reach toml++ 3.3's undefined behaviour is a syntax error naming where.
TEST(MappingFile, TextThatTomlPlusPlus33CannotReadIsASyntaxError) {
  auto quoted_key = parse_mapping("[[device]]\nname = \"x\"\n\"\xc3\xa9\" = 1\n", "pedals.toml");
  ASSERT_FALSE(quoted_key);
  EXPECT_EQ(quoted_key.error().message,
            "pedals.toml:3:2: (syntax): non-ASCII character U+00E9 in a key: keys are ASCII names");
  auto bare = parse_mapping("[[device]]\nname = \"x\"\nusage = 1 \xc2\xa1\n", "pedals.toml");
  ASSERT_FALSE(bare);
  EXPECT_EQ(bare.error().message.rfind("pedals.toml:3:11: (syntax): non-ASCII character U+00A1 outside a string", 0),
            0u)
      << bare.error().message;
  // Names in any language are fine inside strings.
  auto named = parse_mapping("[[device]]\nname = \"Fu\xc3\x9fpedal \xc2\xa1\"\nusage = 4\n"
                             "[[device.binding]]\nresponse = \"go\"\nkind = \"bit\"\nbyte = 0\nbit = 0\n",
                             "pedals.toml");
  ASSERT_TRUE(named) << named.error().message;
  EXPECT_EQ(named.value().devices.at(0).name, "Fu\xc3\x9fpedal \xc2\xa1");
}

TEST(MappingFile, TheDocumentedExampleIsValid) {
  auto r = load_mapping(CURVLAB_DEVICES_DATA "/docs_example.toml");
  ASSERT_TRUE(r) << r.error().message;
  ASSERT_EQ(r.value().devices.size(), 2u);
  EXPECT_EQ(r.value().devices[0].bindings.size(), 2u);
  EXPECT_EQ(r.value().devices[0].report_id, std::uint8_t{1});
  const auto& axis = std::get<AxisBinding>(r.value().devices[0].bindings[1].input);
  EXPECT_EQ(axis.direction, AxisBinding::Direction::Below);
  EXPECT_EQ(axis.press_at, 40);
  EXPECT_EQ(axis.release_at, 90);
  EXPECT_EQ(std::get<KeyBinding>(r.value().devices[1].bindings[0].input).keycode, 0x2C);
}

}  // namespace

// Source URIs: parsing, typed query values, SourceOptions overrides, scheme dispatch.
#include "sources/uri.h"

#include "common/error.h"
#include "core/frame_source.h"
#include "io_test_util.h"
#include "sources/open_source.h"
#include "test_support.h"

namespace emf::sources {
namespace {

using io::testing::expectErrorContaining;

TEST(Uri, ParsesSchemePathAndQuery) {
  const Uri u = parseUri("TUM:/data/fr3 walking?depth_scale=1000&fx=585.5");
  EXPECT_EQ(u.scheme, "tum");
  EXPECT_EQ(u.path, "/data/fr3 walking");
  ASSERT_EQ(u.query.size(), 2u);
  EXPECT_EQ(u.query.at("depth_scale"), "1000");
  EXPECT_EQ(u.query.at("fx"), "585.5");
  const Uri bare = parseUri("openni2:");
  EXPECT_EQ(bare.scheme, "openni2");
  EXPECT_EQ(bare.path, "");
  EXPECT_TRUE(bare.query.empty());
}

TEST(Uri, PercentDecodesPathAndValues) {
  const Uri u = parseUri("klg:/a%3Fb/c%zz.klg?x=1%262&y=");
  EXPECT_EQ(u.path, "/a?b/c%zz.klg");
  EXPECT_EQ(u.query.at("x"), "1&2");
  EXPECT_EQ(u.query.at("y"), "");
}

TEST(Uri, MalformedUrisAreErrorsNamingTheUri) {
  expectErrorContaining([] { parseUri("/data/fr3"); }, {"'/data/fr3'", "no scheme"});
  expectErrorContaining([] { parseUri("t m:/x"); }, {"malformed scheme"});
  expectErrorContaining([] { parseUri("tum:/x?fx"); }, {"'fx' has no '=value'"});
  expectErrorContaining([] { parseUri("tum:/x?=3"); }, {"empty key"});
  expectErrorContaining([] { parseUri("tum:/x?fx=1&fx=2"); }, {"'fx' given twice"});
}

TEST(UriQuery, UnknownKeyIsNamedWithTheValidOnes) {
  const Uri u = parseUri("tum:/x?depth_scael=1000");
  expectErrorContaining([&] { UriQuery q(u, sourceQueryKeys()); },
                        {"unknown query key 'depth_scael'", "scheme 'tum:'",
                         "valid keys:", "depth_scale", "max_frames"});
}

TEST(UriQuery, TypedValuesAndRanges) {
  const Uri u = parseUri("x:/p?a=2.5&b=7&c=abc&d=-1");
  const UriQuery q(u, {"a", "b", "c", "d", "e"});
  EXPECT_DOUBLE_EQ(*q.real("a", 0, 10), 2.5);
  EXPECT_EQ(*q.integer("b", 0, 10), 7);
  EXPECT_FALSE(q.real("e", 0, 1).has_value());
  expectErrorContaining([&] { q.real("c", 0, 1); }, {"'c' must be a number, got 'abc'"});
  expectErrorContaining([&] { q.integer("a", 0, 10); }, {"'a' must be an integer"});
  expectErrorContaining([&] { q.integer("d", 0, 10); }, {"'d' = -1 is outside its range"});
}

TEST(UriQuery, OverridesSourceOptionsWithConfigRanges) {
  core::SourceOptions base;
  base.fx = 500;
  base.cy = 10;
  const Uri u = parseUri("tum:/x?depth_scale=1000&fx=585&max_frames=12&max_time_diff_s=0.05");
  const core::SourceOptions o = applySourceQuery(UriQuery(u, sourceQueryKeys()), base);
  EXPECT_EQ(o.depth_scale, 1000.0);
  EXPECT_EQ(o.fx, 585.0);
  EXPECT_EQ(o.cy, 10.0);  // not in the query: kept
  EXPECT_EQ(o.max_frames, 12);
  EXPECT_EQ(o.max_time_diff_s, 0.05);
  const Uri bad = parseUri("tum:/x?depth_scale=0");
  expectErrorContaining([&] { applySourceQuery(UriQuery(bad, sourceQueryKeys()), base); },
                        {"'depth_scale' = 0 is outside its range"});
  // `uri` is a config key but not a query key.
  expectErrorContaining([] { UriQuery(parseUri("tum:/x?uri=y"), sourceQueryKeys()); },
                        {"unknown query key 'uri'"});
}

TEST(OpenSource, DispatchErrorsSayWhatToDo) {
  const core::SourceOptions o;
  expectErrorContaining([&] { openSource("foo:/x", o); }, {"unknown scheme 'foo:'", "tum:<dir>"});
  // synth: and the sensors are dispatched to their modules, which name what is wrong.
  expectErrorContaining([&] { openSource("synth:nosuchpreset", o); },
                        {"unknown preset 'nosuchpreset'", "room"});
  expectErrorContaining([&] { openSource("synth:", o); }, {"missing preset name"});
  EXPECT_EQ(openSource("synth:room?frames=3&width=64&height=48", o)->size(), 3);
  expectErrorContaining([&] { openSource("v4l2:/dev/emf-no-such-video", o); },
                        {"/dev/emf-no-such-video"});
  expectErrorContaining([&] { openSource("tum:", o); }, {"missing dataset folder"});
  expectErrorContaining([&] { openSource("tum:/nonexistent-emf-folder", o); },
                        {"'/nonexistent-emf-folder' does not exist"});
  expectErrorContaining([&] { openSource("klg:/x.klg?fps=3", o); },
                        {"unknown query key 'fps'", "width"});
  expectErrorContaining([&] { openSource("cofusion:/x?depth_scale=3", o); },
                        {"unknown query key 'depth_scale'", "fps"});
}

}  // namespace
}  // namespace emf::sources

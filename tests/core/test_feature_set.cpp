// The shared vocabulary (core/feature_set.h): one parser of invariant lists for the command
// line, Python and the JSON record, so that "V,S,P,L", "VSPL" and "v, s" mean the same
// everywhere, and a wrong entry gets one sentence naming the right ones.
#include <msii/core/errors.h>
#include <msii/core/feature_set.h>

#include <gtest/gtest.h>

#include <string>
#include <vector>

using namespace msii;

TEST(FeatureSet, InvariantListsAreParsedAlikeInEverySpelling)
{
    const std::vector<Invariant> all(kAllInvariants.begin(), kAllInvariants.end());
    for (const char* text : {"V,S,P,L", "VSPL", "vspl", "v, s, p, l", "V S P L", " VS,pl "})
        EXPECT_EQ(parseInvariantList(text), all) << text;
    const std::vector<Invariant> vs{Invariant::Volume, Invariant::Sphere};
    for (const char* text : {"v, s", "VS", "V,S", "vs"}) EXPECT_EQ(parseInvariantList(text), vs) << text;
    EXPECT_EQ(parseInvariantList("P,V"), (std::vector<Invariant>{Invariant::Patch, Invariant::Volume}));  // order kept
    EXPECT_EQ(invariantLetters(all), "VSPL");
    EXPECT_EQ(parseInvariantList(invariantLetters(vs)), vs);
}

TEST(FeatureSet, AWrongInvariantListGetsOneSentence)
{
    const auto message = [](const std::string& text) {
        try {
            parseInvariantList(text);
        } catch (const InvalidInputError& e) {
            return std::string(e.what());
        }
        return std::string("accepted");
    };
    const std::string q = message("V,Q");
    EXPECT_NE(q.find("unknown invariant 'Q'"), std::string::npos) << q;
    EXPECT_NE(q.find("V, S, P and L"), std::string::npos) << q;
    EXPECT_NE(message("Volume").find("unknown invariant 'Volume'"), std::string::npos);
    EXPECT_NE(message("V,v").find("listed twice"), std::string::npos);
    EXPECT_NE(message(" , ").find("selects nothing"), std::string::npos);
    for (const char* text : {"V,Q", "Volume", "V,v", ""}) EXPECT_EQ(message(text).find('\n'), std::string::npos);
}

// The features as named outputs (io/feature_properties.h): their names, one parser of
// feature-name lists (the bands of a DEM's GeoTIFF), and the formula legend written into
// every output.
#include <msii/core/errors.h>
#include <msii/io/feature_properties.h>

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

using namespace msii;

TEST(FeatureProperties, NamesFollowTheProperties)
{
    FeatureSet f;
    f.radii = {1, 2};
    f[Invariant::Volume] = {{0.5f, 0.4f}, {0.5f, NAN}};
    f[Invariant::Line] = {{1.0f, 1.0f}, {1.0f, 1.1f}};
    const std::vector<VertexProperty> props = outputProperties(f, {0.0f, 0.25f});
    const std::vector<std::string> names = outputPropertyNames({Invariant::Volume, Invariant::Line}, 2);
    ASSERT_EQ(props.size(), names.size());
    for (std::size_t k = 0; k < names.size(); ++k) EXPECT_EQ(props[k].name, names[k]);
    EXPECT_EQ(names, (std::vector<std::string>{"V_01", "V_02", "L_01", "L_02", "quality", "valid_radii", "filled_share"}));
    EXPECT_EQ(props.back().values[1], 0.25f);
    EXPECT_EQ(props[4].values[1], 0.4f);  // quality: V at the largest radius with a value
}

TEST(FeatureProperties, FeatureNameListsAreParsedAgainstWhatIsThere)
{
    const std::vector<std::string> available = outputPropertyNames({Invariant::Volume, Invariant::Sphere}, 16);
    EXPECT_EQ(parseFeatureNames("quality,V_04, s_16", available), (std::vector<std::string>{"quality", "V_04", "S_16"}));
    EXPECT_EQ(parseFeatureNames("Filled_Share valid_radii", available),
              (std::vector<std::string>{"filled_share", "valid_radii"}));
    const auto message = [&](const std::string& text) {
        try {
            parseFeatureNames(text, available);
        } catch (const InvalidInputError& e) {
            return std::string(e.what());
        }
        return std::string("accepted");
    };
    const std::string wrong = message("quality,V_99");
    EXPECT_NE(wrong.find("no feature 'V_99'"), std::string::npos) << wrong;
    EXPECT_NE(wrong.find("V_01 ... V_16, S_01 ... S_16, quality, valid_radii, filled_share"), std::string::npos) << wrong;
    EXPECT_NE(message("P_04").find("no feature 'P_04'"), std::string::npos);  // P was not computed
    EXPECT_NE(message(",").find("selects nothing"), std::string::npos);
}

TEST(FeatureProperties, TheLegendStatesEachNormalisation)
{
    EXPECT_EQ(featureLegend(), "V_jj = V/|B_r|, S_jj = S/(4 pi r^2) (plane 0.5), P_jj = P/(pi r^2), "
                               "L_jj = L/(2 pi r) (plane 1), r_j = j*R/N");
    EXPECT_EQ(invariantConvention(Invariant::Volume), "V/|B_r| in [0,1], flat plane 0.5, convex < 0.5");
    EXPECT_EQ(invariantConvention(Invariant::Patch), "P/(pi r^2), flat plane 1");
}

// The report module's building blocks: escaping, relative links, base64, JSON in HTML.
#include <gtest/gtest.h>
#include <tdf/report/html.h>

#include <filesystem>

namespace tdf {
namespace {

TEST(ReportHtml, EscapesMarkupCharacters) {
    EXPECT_EQ(html_escape("<a href='x'>\"R&D\"</a>"),
              "&lt;a href=&#39;x&#39;&gt;&quot;R&amp;D&quot;&lt;/a&gt;");
    EXPECT_EQ(html_escape("plain text 123"), "plain text 123");
}

TEST(ReportHtml, RelativeUrlsArePercentEncodedAndRelative) {
    EXPECT_EQ(relative_url("/tmp/run/turntable/albedo_000.png", "/tmp/run"), "turntable/albedo_000.png");
    EXPECT_EQ(relative_url("/tmp/run/a b/c#1.png", "/tmp/run"), "a%20b/c%231.png");
    EXPECT_EQ(relative_url("/tmp/other/x.png", "/tmp/run"), "../other/x.png");
    // Relative inputs are taken from the working directory, like every other path.
    EXPECT_EQ(relative_url("out/run/x.png", "out/run"), "x.png");
}

TEST(ReportHtml, Base64MatchesRfc4648Vectors) {
    EXPECT_EQ(base64_encode(""), "");
    EXPECT_EQ(base64_encode("f"), "Zg==");
    EXPECT_EQ(base64_encode("fo"), "Zm8=");
    EXPECT_EQ(base64_encode("foo"), "Zm9v");
    EXPECT_EQ(base64_encode("foob"), "Zm9vYg==");
    EXPECT_EQ(base64_encode("fooba"), "Zm9vYmE=");
    EXPECT_EQ(base64_encode("foobar"), "Zm9vYmFy");
    EXPECT_EQ(base64_encode(std::string("\xff\x00\x80", 3)), "/wCA");
}

TEST(ReportHtml, JsonCannotCloseAScriptBlock) {
    const std::string text = json_for_html(Json{{"name", "</script><b>&'"}});
    EXPECT_EQ(text.find('<'), std::string::npos);
    EXPECT_EQ(text.find('>'), std::string::npos);
    EXPECT_EQ(text.find('\''), std::string::npos);
    EXPECT_EQ(parse_json(text, "test")["name"], "</script><b>&'");
}

TEST(ReportHtml, NumbersAreReadable) {
    EXPECT_EQ(format_number(12), "12");
    EXPECT_EQ(format_number(0.123456), "0.1235");
    EXPECT_EQ(format_number(std::numeric_limits<double>::infinity()), "inf");
    EXPECT_EQ(format_json_value(Json("pass")), "pass");
    EXPECT_EQ(format_json_value(Json(true)), "true");
}

}  // namespace
}  // namespace tdf

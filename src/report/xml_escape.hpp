// Text made safe for XML and HTML element content and attribute values. Control characters
// other than tab and newline are not allowed in XML 1.0 and become spaces.
#pragma once

#include <string>
#include <string_view>

namespace mbstorm::report {

std::string xml_escape(std::string_view text);

}  // namespace mbstorm::report

// Text taken from files and paths, made safe for where it goes: HTML text and attribute values,
// and JSON strings. Every page or report the tool writes passes such text through these.
#pragma once

#include <string>

namespace prtsub {

//! For HTML text and quoted attribute values: & < > " ' become entities.
std::string html_escape(const std::string& text);

//! A JSON string literal, quotes included: " \ and control characters escaped, and < > & as
//! \u003c \u003e \u0026, so the literal is also safe inside an HTML <script> block.
std::string json_quote(const std::string& text);

}  // namespace prtsub

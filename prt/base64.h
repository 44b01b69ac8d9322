// Base64 (RFC 4648, with padding): glTF's data: URIs and the viewer page's embedded bytes.
#pragma once

#include <string>

namespace prtsub {

std::string base64_encode(const std::string& bytes);

//! Decodes `text` from offset `from`; false if it holds a character outside the alphabet or
//! padding before the end.
bool base64_decode(const std::string& text, size_t from, std::string& out);

}  // namespace prtsub

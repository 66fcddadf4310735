// Reading back the arrays of crumble's .vtp files in either encoding (output.vtk_format):
// ascii text, or binary (VTK XML 1.0, UInt64 header [1, n, n, c] base64-encoded on its own,
// then the n bytes zlib-compressed to c and base64-encoded), as output/VtkWriter.cpp lays them out.
#pragma once
#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace crumble::test {

inline std::string base64_decoded(const std::string& t) {
  std::string out;
  unsigned v = 0;
  int bits = 0;
  for (char ch : t) {
    const auto at = std::string_view("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/").find(ch);
    if (at == std::string_view::npos) continue;  // padding, line ends
    v = (v << 6) | static_cast<unsigned>(at);
    if ((bits += 6) >= 8) out += static_cast<char>((v >> (bits -= 8)) & 0xff);
  }
  return out;
}

// The values of a binary array's text (the body between its DataArray tags).
inline std::vector<double> binary_values(const std::string& t, bool integer) {
  const std::string head = base64_decoded(t.substr(0, 44));  // 32 bytes: 44 characters
  std::uint64_t h[4] = {};
  if (head.size() >= sizeof h) std::memcpy(h, head.data(), sizeof h);
  EXPECT_EQ(h[0], 1u);
  const std::string z = base64_decoded(t.substr(std::min<std::size_t>(44, t.size())));
  std::vector<unsigned char> raw(h[1]);
  uLongf n = raw.size();
  EXPECT_EQ(uncompress(raw.data(), &n, reinterpret_cast<const Bytef*>(z.data()), h[3]), Z_OK);
  std::vector<double> v(n / 8);
  for (std::size_t i = 0; i < v.size(); ++i) {
    std::int64_t k;
    if (integer) std::memcpy(&k, raw.data() + 8 * i, 8), v[i] = static_cast<double>(k);
    else std::memcpy(&v[i], raw.data() + 8 * i, 8);
  }
  return v;
}

// The values of a DataArray from its opening tag and its body, in either encoding.
inline std::vector<double> data_array_values(const std::string& tag, const std::string& body) {
  if (tag.find("format=\"binary\"") != std::string::npos)
    return binary_values(body, tag.find("type=\"Int64\"") != std::string::npos);
  std::vector<double> v;
  std::istringstream in(body);
  for (double x; in >> x;) v.push_back(x);
  return v;
}

// The values of DataArray `name` of a .vtp text, every component.
inline std::vector<double> vtp_array(const std::string& text, const std::string& name) {
  const auto at = text.find("Name=\"" + name + "\"");
  if (at == std::string::npos) return {};
  const auto open = text.rfind('<', at), start = text.find('\n', at) + 1;
  return data_array_values(text.substr(open, start - open),
                           text.substr(start, text.find("</DataArray>", at) - start));
}

}  // namespace crumble::test

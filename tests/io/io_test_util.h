// Helpers shared by the io tests: writing small files and asserting on error messages.
#pragma once

#include <gtest/gtest.h>

#include <functional>
#include <string>

namespace emf::io::testing {

/// Writes `text` to `path` (creating parent folders).
void writeText(const std::string& path, const std::string& text);

/// Runs `f`, expecting it to throw an emf::Error whose message contains every string in
/// `needles`; returns the message.
std::string expectErrorContaining(const std::function<void()>& f,
                                  const std::vector<std::string>& needles);

}  // namespace emf::io::testing

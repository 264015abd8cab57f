// The name of a table-driven test's row for gtest: the row's `name` with every character but
// letters and digits turned into '_' (gtest accepts nothing else).
#pragma once

#include <gtest/gtest.h>

#include <cctype>
#include <string>

namespace ncservo::test {

template <typename Row>
std::string rowName(const ::testing::TestParamInfo<Row>& row) {
  std::string name = row.param.name;
  for (char& c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  }
  return name;
}

}  // namespace ncservo::test

#include <cstdio>

#include "delta/core/version.h"
int main() {
  std::printf("%s\n", delta::version());
}

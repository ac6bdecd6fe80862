#include <CLI/CLI.hpp>
int main(int argc, char** argv) {
  CLI::App app{"screwfem: geometrically exact screw-based FEM for soft robots"};
  CLI11_PARSE(app, argc, argv);
  return 0;
}

#include <CLI/CLI.hpp>
int main(int argc, char** argv) {
    CLI::App app{"btf: inspect, generate and fit measured BTFs"};
    CLI11_PARSE(app, argc, argv);
    return 0;
}

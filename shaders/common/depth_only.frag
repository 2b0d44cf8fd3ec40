#version 330 compatibility
// A shadow technique's depth pass over a MaterialNode (scene/MaterialNode.cpp) writes depth only:
// no BTF is evaluated for a fragment nobody sees.
void main() {
}

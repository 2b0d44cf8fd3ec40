#version 330 compatibility
// A shadow technique's depth pass over a MaterialNode (scene/MaterialNode.cpp): the position the
// fixed-function pipeline would compute, and nothing else.
void main() {
    gl_Position = ftransform();
}

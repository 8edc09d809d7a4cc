#version 430
// The cheapest dispatch: what every pass pays before it does anything.
layout(local_size_x = LOCAL_SIZE) in;
void main() {}

#include <iostream>
int main() { std::cout << "crumble\n"; }

fn main() {
    // Debian's libembree-dev: /usr/lib/x86_64-linux-gnu/libembree3.so.
    println!("cargo:rustc-link-lib=dylib=embree3");
}

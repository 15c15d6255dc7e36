fn main() {
    println!("glint");
}

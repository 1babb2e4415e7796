fn main() {
    println!("vkvcm");
}

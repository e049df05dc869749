fn main() {
    let c = [-9.469771e19f32, 57762063000000.0, -9734343.0, 0.5];
    println!("{:?}", nlrt_poly::solve_cubic(c));
}

fn main() {
    let p = std::env::args().nth(1).unwrap();
    let (film, _) = splitray::film::read_exr(&p).unwrap();
    let w = film.width();
    for (x, y) in [(32u32, 32u32), (10, 32), (54, 32), (32, 60)] {
        println!("{x},{y}: {:?}", film.mean_rgb((y * w + x) as usize));
    }
}

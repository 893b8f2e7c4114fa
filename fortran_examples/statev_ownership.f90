! statev_ownership.f90 -- the state a host hands over must be this point's, through the
! Fortran module's rve_umat in STATEV mode: a valid STATEV of another point, of an older
! increment, of another scene, of other PROPS, of another integration or of an edited scene
! is refused with a message, PNEWDT < 1, STRESS and STATEV untouched; the same state at its
! own strain answers at a new point; a comment-only edit of the scene is no change.
! The same rows as c_examples/statev_ownership.c, over the scene variants that
! scripts/ownership-scenes writes (PAPER, SHEAR, IMPLEX, EDIT_SIGMA, EDIT_COMMENT).
!
! Usage: MESORVE_SCENE_PATH=DIR statev_ownership NSTATV NSTATV_IMPLEX
! Exit status 0 when every check passed.
program statev_ownership
  use, intrinsic :: iso_c_binding, only: c_char, c_double, c_int, c_size_t
  use rve, only: rve_umat, rve_last_error
  implicit none

  integer, parameter :: mirrors = 3
  real(c_double), parameter :: untouched = 7.0_c_double, step = 1.15e-5_c_double
  integer :: checks = 0, failures = 0, n, n_implex, room
  real(c_double), allocatable :: damaged(:), elastic(:), at_10(:), other(:), work(:), &
      whole(:), half(:)
  real(c_double) :: own_stress(3), moved_stress(3), pnewdt
  character(len=64) :: arg
  character(len=2048) :: msg
  logical :: failed
  integer :: k

  if (command_argument_count() /= 2) then
    write (*, '(a)') 'usage: MESORVE_SCENE_PATH=DIR statev_ownership NSTATV NSTATV_IMPLEX'
    stop 2
  end if
  call get_command_argument(1, arg)
  read (arg, *) n
  call get_command_argument(2, arg)
  read (arg, *) n_implex
  room = max(n, n_implex) + mirrors
  allocate (damaged(room), elastic(room), at_10(room), other(room), work(room), &
      whole(room), half(room))

  call run('PAPER', 0.0_c_double, n, 1, 20, damaged)
  call run('PAPER', 0.0_c_double, n, 2, 5, elastic)
  call run('PAPER', 0.0_c_double, n, 3, 10, at_10)
  call refused('another point''s, damaged, to a smaller strain', 'PAPER', 0.0_c_double, n, &
      4, 6, damaged, 'not the state of this point')
  call refused('another point''s, elastic, to a damaged point', 'PAPER', 0.0_c_double, n, &
      5, 21, elastic, 'not the state of this point')
  call refused('a stale one (two increments old)', 'PAPER', 0.0_c_double, n, 6, 13, at_10, &
      'not the state of this point')
  work = at_10
  other = at_10
  call umat_call('PAPER', 0.0_c_double, n, 3, 11, work, own_stress, pnewdt, failed, msg)
  call expect(.not. failed, 'its own point answers')
  call umat_call('PAPER', 0.0_c_double, n, 7, 11, other, moved_stress, pnewdt, failed, msg)
  call expect(.not. failed .and. all(abs(moved_stress - own_stress) <= 0), &
      'the same state at its own strain answers at a new point')
  call run('SHEAR', 0.0_c_double, n, 8, 10, other)
  call refused('another scene''s of the same size', 'PAPER', 0.0_c_double, n, 9, 11, other, &
      'fingerprint')
  call run('PAPER', 3.6_c_double, n, 10, 10, other)
  call refused('PROPS(1) 3.6 written, 4 handed', 'PAPER', 4.0_c_double, n, 11, 11, other, &
      'fingerprint')
  call refused('PROPS(1) 4 written, 3.6 handed', 'PAPER', 3.6_c_double, n, 12, 11, at_10, &
      'fingerprint')
  other = 0
  other(1:n) = at_10(1:n)
  call refused('an implicit scene''s, handed to IMPL-EX', 'IMPLEX', 0.0_c_double, n_implex, &
      13, 11, other, 'fingerprint')
  call run('PAPER', 0.0_c_double, n, 14, 8, other)
  call refused('PROPS changed in the middle of an analysis', 'PAPER', 3.6_c_double, n, 14, &
      9, other, 'fingerprint')
  other = 0
  call refused('all zeros at a strained point', 'PAPER', 0.0_c_double, n, 15, 11, other, &
      'contact pair')
  ! The scene edited between two parts: the second part's material names the edited copy.
  call run('PAPER', 0.0_c_double, n, 30, 12, whole)
  call run('PAPER', 0.0_c_double, n, 31, 8, half)
  work = half
  do k = 9, 12
    call umat_call('EDIT_COMMENT', 0.0_c_double, n, 31, k, work, own_stress, pnewdt, &
        failed, msg)
    call expect(.not. failed, 'a comment-only edit: accepted')
  end do
  call expect(all(abs(work(1:n) - whole(1:n)) <= 0), &
      'a comment-only edit: the whole run bit for bit')
  call refused('the scene edited between the parts (sigma_c)', 'EDIT_SIGMA', 0.0_c_double, &
      n, 32, 9, half, 'fingerprint')
  write (*, '(a, i0, a, i0, a)') 'statev_ownership: ', checks, ' checks, ', failures, ' failed'
  deallocate (damaged, elastic, at_10, other, work, whole, half)
  if (failures > 0) stop 1

contains

  subroutine expect(ok, what)
    logical, intent(in) :: ok
    character(len=*), intent(in) :: what
    checks = checks + 1
    if (.not. ok) then
      failures = failures + 1
      write (*, '(2a)') 'FAILED: ', what
    end if
  end subroutine expect

  ! Increment k of point noel: STRAN = (k-1) steps, DSTRAN one step in eps_xx; plane
  ! stress, NSTATV = nstatv + mirrors, PROPS(1) = prop1 (0: the scene's).
  subroutine umat_call(name, prop1, nstatv, noel, k, statev, stress, pnewdt, failed, msg)
    character(len=*), intent(in) :: name
    real(c_double), intent(in) :: prop1
    integer, intent(in) :: nstatv, noel, k
    real(c_double), intent(inout) :: statev(:)
    real(c_double), intent(out) :: stress(3), pnewdt
    logical, intent(out) :: failed
    character(len=*), intent(out) :: msg
    character(kind=c_char, len=80) :: cmname
    real(c_double) :: ddsdde(9), sse, spd, scd, rpl, ddsddt(3), drplde(3), drpldt
    real(c_double) :: stran(3), dstran(3), time(2), props(1), coords(3), drot(3, 3), &
        dfgrd(3, 3), predef(1), dpred(1)
    integer(c_int) :: nstatv_c, nprops
    integer(c_size_t) :: length
    character(kind=c_char, len=2048) :: buf
    sse = 0; spd = 0; scd = 0; rpl = 0; ddsddt = 0; drplde = 0; drpldt = 0
    stran = [(k - 1) * step, 0.0_c_double, 0.0_c_double]
    dstran = [step, 0.0_c_double, 0.0_c_double]
    time = 0.1_c_double * (k - 1)
    props(1) = prop1
    nprops = merge(1, 0, abs(prop1) > 0)
    coords = 0; predef = 0; dpred = 0
    drot = reshape([1, 0, 0, 0, 1, 0, 0, 0, 1], [3, 3])
    dfgrd = drot
    cmname = name
    nstatv_c = nstatv + mirrors
    stress = untouched
    pnewdt = 1e36_c_double
    call rve_umat(stress, statev, ddsdde, sse, spd, scd, rpl, ddsddt, drplde, drpldt, &
        stran, dstran, time, 0.1_c_double, 20.0_c_double, 0.0_c_double, predef, dpred, &
        cmname, 2, 1, 3, nstatv_c, props, nprops, coords, drot, pnewdt, 1.0_c_double, &
        dfgrd, dfgrd, noel, 1, 0, 0, 1, k, 80_c_size_t)
    length = rve_last_error(buf, len(buf, kind=c_size_t))
    failed = length > 0
    msg = ''
    if (failed) msg = buf(1:min(int(length), len(msg)))
  end subroutine umat_call

  ! Point noel through increments 1..last from zeros; statev holds the state at the end.
  subroutine run(name, prop1, nstatv, noel, last, statev)
    character(len=*), intent(in) :: name
    real(c_double), intent(in) :: prop1
    integer, intent(in) :: nstatv, noel, last
    real(c_double), intent(inout) :: statev(:)
    real(c_double) :: stress(3), pnewdt
    character(len=2048) :: msg
    logical :: failed
    integer :: k
    statev = 0
    do k = 1, last
      call umat_call(name, prop1, nstatv, noel, k, statev, stress, pnewdt, failed, msg)
      if (failed) then
        write (*, '(a, i0, 2a)') 'increment ', k, ': ', trim(msg)
        stop 1
      end if
    end do
  end subroutine run

  ! statev handed to point noel at increment k: refused with `needle` in the message,
  ! PNEWDT < 1, STRESS and STATEV untouched.
  subroutine refused(what, name, prop1, nstatv, noel, k, statev, needle)
    character(len=*), intent(in) :: what, name, needle
    real(c_double), intent(in) :: prop1
    integer, intent(in) :: nstatv, noel, k
    real(c_double), intent(in) :: statev(:)
    real(c_double) :: copy(size(statev)), stress(3), pnewdt
    character(len=2048) :: msg
    logical :: failed
    copy = statev
    call umat_call(name, prop1, nstatv, noel, k, copy, stress, pnewdt, failed, msg)
    call expect(failed .and. index(msg, needle) > 0, what // ': refused, the message names it')
    call expect(pnewdt < 1 .and. all(abs(stress - untouched) <= 0) .and. &
      all(abs(copy - statev) <= 0), &
        what // ': PNEWDT < 1, STRESS and STATEV untouched')
    write (*, '(a, t50, a)') what, msg(1:min(len_trim(msg), 120))
  end subroutine refused

end program statev_ownership

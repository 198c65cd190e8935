;;;; tests/run.lisp -- run the claims of physics.org; the last line says "N passed, N failed".
;;;;
;;;; Usage: sbcl --non-interactive --no-sysinit --no-userinit --load tests/run.lisp
;;;; With ANCHOR=XXXXXX in the environment, only the claims of that section run.
;;;; A claim passes when it made at least one check and every check passed.
;;;; Exit status: 0 if every selected claim passed, 1 otherwise (or if none ran),
;;;; 2 if the systems did not load.

(load (merge-pathnames "../tools/boot.lisp" *load-truename*))

(in-package #:cl-user)

(defun finish-claims (passed failed code)
  "Print the closing summary line and exit with CODE."
  (format t "~&~D passed, ~D failed~%" passed failed)
  (finish-output)
  (sb-ext:exit :code code))

(when (luv-load-systems "luv-physics/tests")
  (finish-claims 0 1 2))

(defun claim-passed-p (name results)
  "True if the FiveAM RESULTS of test NAME are not empty and all passed."
  (let ((own (remove name results :key (lambda (r) (5am::name (5am::test-case r))) :test-not #'eq)))
    (and own (every #'5am::test-passed-p own))))

(let* ((anchor (string-upcase (string-trim " #" (or (sb-ext:posix-getenv "ANCHOR") ""))))
       (all (string= anchor ""))
       (selected (if all
                     luv-physics-tests:*claims*
                     (remove anchor luv-physics-tests:*claims* :key #'car :test-not #'string=))))
  (when (null selected)
    (if all
        (format t "~&No claims are defined.~%")
        (format t "~&No claims for anchor ~A. Anchors with claims: ~{~A~^ ~}~%"
                anchor (remove-duplicates (mapcar #'car luv-physics-tests:*claims*)
                                          :test #'string= :from-end t)))
    (finish-claims 0 0 1))
  (let ((results (5am:run (if all
                              'luv-physics-tests:claims
                              (find-symbol anchor '#:luv-physics-tests)))))
    (5am:explain! results)
    (let ((failed (count-if-not (lambda (claim) (claim-passed-p (cdr claim) results)) selected)))
      (finish-claims (- (length selected) failed) failed (if (zerop failed) 0 1)))))
